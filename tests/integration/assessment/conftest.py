"""Accounts in two courses on the live app (the bookings fixtures)."""

from __future__ import annotations

from tests.integration.bookings.conftest import api, client_as, course_people

__all__ = ["api", "client_as", "course_people"]
