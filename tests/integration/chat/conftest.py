"""Chat tests reuse the accounts and helpers of the booking tests."""

from tests.integration.bookings.conftest import client_as, course_people  # noqa: F401
