"""Accounts in two courses on the live app (the bookings fixtures)."""

from __future__ import annotations

import pytest

from tests.integration.bookings.conftest import api, client_as, course_people

__all__ = ["api", "client_as", "course_people"]


@pytest.fixture(autouse=True)
def _no_recorder_outlives_its_test():
    """A test that leaves an attempt unsettled leaves its recorder running in this process, keyed by the attempt's
    id; the next test's fresh database numbers its attempts from 1 again, and would find that recorder."""
    yield
    from middleware.assessment import recorder

    for attempt_id in list(recorder._recorders):
        recorder.stop(attempt_id)
