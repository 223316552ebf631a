"""The week page shows slots the viewer cannot book as unavailable, with the reason, instead of "free"
(issue 14, failure 5): a student in no course, a student whose week's minutes are used; tutors see free slots."""

from __future__ import annotations

import re
from datetime import UTC, datetime, timedelta

from tests.conftest import LabClient
from tests.integration.bookings.conftest import api

NEXT_MONDAY = (datetime.now(UTC) + timedelta(days=7 - datetime.now(UTC).weekday())).replace(
    hour=9, minute=0, second=0, microsecond=0)


def week_page(client: LabClient, monday: datetime) -> str:
    status, _, body = client.request("GET", f"/bookings?robot=lab-1&tz=UTC&week={monday:%Y-%m-%d}")
    assert status == 200
    return body


def cells(body: str, kind: str) -> int:
    return len(re.findall(rf'class="slot slot--{kind}"', body))


def test_a_student_in_no_course_sees_every_slot_unavailable_and_why(student_client: LabClient) -> None:
    body = week_page(student_client, NEXT_MONDAY)
    assert cells(body, "free") == 0 and cells(body, "unavailable") == 7 * 30
    assert 'data-unavailable="not in a course"' in body
    assert "You are not enrolled in any course, so you cannot book a robot yet" in body


def test_a_student_with_no_minutes_left_that_week_sees_it_unavailable_and_the_next_week_free(
        client_as, course_people) -> None:
    student = client_as("student1")
    start = NEXT_MONDAY.strftime("%Y-%m-%dT%H:%M:%SZ")
    assert api(student, "POST", "/api/bookings", {"robot_name": "lab-1", "starts_at": start,
                                                   "duration_min": 120})[0] == 201
    body = week_page(student, NEXT_MONDAY)
    assert cells(body, "free") == 0 and cells(body, "mine") == 4
    assert cells(body, "unavailable") == 7 * 30 - 4
    assert "You have booked all 120 minutes your course allows" in body
    later = week_page(student, NEXT_MONDAY + timedelta(days=7))
    assert cells(later, "unavailable") == 0 and cells(later, "free") == 7 * 30
    assert 'id="unavailable-reasons"' not in later


def test_a_tutor_sees_free_slots_and_the_students_booking_as_taken(client_as, course_people) -> None:
    student = client_as("student1")
    start = NEXT_MONDAY.strftime("%Y-%m-%dT%H:%M:%SZ")
    assert api(student, "POST", "/api/bookings", {"robot_name": "lab-1", "starts_at": start,
                                                   "duration_min": 30})[0] == 201
    body = week_page(client_as("tutor1"), NEXT_MONDAY)
    assert cells(body, "unavailable") == 0 and cells(body, "taken") == 1 and cells(body, "free") == 7 * 30 - 1
