"""The same people, courses and before/after snapshot as the accounts tests."""

from __future__ import annotations

from tests.integration.accounts.conftest import api, client_as, course_people, snapshot

__all__ = ["api", "client_as", "course_people", "snapshot"]
