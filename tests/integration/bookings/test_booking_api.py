"""The booking API and pages over HTTP: who may do what, errors naming fields, the iCalendar export."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest

from tests.integration.bookings.conftest import api

START = (datetime.now(UTC) + timedelta(days=2)).replace(hour=9, minute=0, second=0, microsecond=0)


def iso(moment: datetime) -> str:
    return moment.strftime("%Y-%m-%dT%H:%M:%SZ")


def slot(offset_h: int = 0, minutes: int = 30, **extra: object) -> dict[str, object]:
    start = START + timedelta(hours=offset_h)
    return {"robot_name": "lab-1", "starts_at": iso(start), "ends_at": iso(start + timedelta(minutes=minutes)),
            **extra}


def booking_rows(app) -> list[tuple]:
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import Booking

    with session_factory(app)() as session:
        return [tuple(r) for r in session.execute(
            select(Booking.id, Booking.user_id, Booking.kind, Booking.cancelled_at).order_by(Booking.id))]


def test_a_student_books_lists_and_cancels(client_as, app) -> None:
    student = client_as("student1")
    status, body = api(student, "POST", "/api/bookings", slot())
    assert status == 201 and body["booking"]["status"] == "booked" and body["booking"]["mine"]
    booking_id = body["booking"]["id"]
    status, body = api(student, "GET", "/api/bookings")
    assert [b["id"] for b in body["bookings"]] == [booking_id]
    status, body = api(student, "GET", f"/api/robots/lab-1/bookings?from={iso(START - timedelta(days=1))}"
                                       f"&to={iso(START + timedelta(days=1))}")
    assert status == 200 and [b["id"] for b in body["bookings"]] == [booking_id]
    assert api(student, "DELETE", f"/api/bookings/{booking_id}")[0] == 200
    assert api(client_as("student2"), "POST", "/api/bookings", slot())[0] == 201, "the slot is free again"


@pytest.mark.parametrize(("body", "field"), [
    ({"robot_name": "lab-1", "starts_at": "tomorrow", "ends_at": "2031-01-01T10:00:00Z"}, "starts_at"),
    ({"robot_name": "lab-1", "starts_at": "2031-01-01T10:00:00", "ends_at": "2031-01-01T10:30:00Z"}, "starts_at"),
    ({"robot_name": "lab-1", "starts_at": "2031-01-01T10:00:00Z"}, "ends_at"),
    ({"robot_name": "", "starts_at": "2031-01-01T10:00:00Z", "ends_at": "2031-01-01T10:30:00Z"}, "robot_name"),
    ({"robot_name": "nope", "starts_at": "2031-01-01T10:00:00Z", "ends_at": "2031-01-01T10:30:00Z"}, "robot_name"),
    ({"robot_name": "lab-1", "starts_at": "2031-01-01T10:10:00Z", "ends_at": "2031-01-01T10:40:00Z"}, "starts_at"),
    ({"robot_name": "lab-1", "starts_at": "2031-01-01T10:00:00Z", "ends_at": "2031-01-01T15:00:00Z"}, "ends_at"),
    ({"robot_name": "lab-1", "starts_at": "2001-01-01T10:00:00Z", "ends_at": "2001-01-01T10:30:00Z"}, "starts_at"),
    ({"robot_name": "lab-1", "starts_at": "2031-01-01T10:00:00Z", "ends_at": "2031-01-01T10:30:00Z",
      "kind": "party"}, "kind"),
    ({"robot_name": "lab-1", "starts_at": 5, "ends_at": "2031-01-01T10:30:00Z"}, "starts_at"),
    ([1, 2], "body"),
])
def test_bad_booking_requests_name_the_field_and_change_nothing(client_as, app, body, field) -> None:
    status, answer = api(client_as("admin1"), "POST", "/api/bookings", body)
    assert status in (400, 404) and answer["error"]["field"] == field, answer
    assert booking_rows(app) == []


def test_an_overlap_is_refused_with_409_naming_starts_at(client_as, app) -> None:
    assert api(client_as("student1"), "POST", "/api/bookings", slot(0, 60))[0] == 201
    status, body = api(client_as("student2"), "POST", "/api/bookings", slot(0, 30))
    assert status == 409 and body["error"] == {"code": "slot_taken", "field": "starts_at",
                                               "message": body["error"]["message"]}
    assert len(booking_rows(app)) == 1


# Who may create: (account, request extras, expected status). None is the anonymous visitor.
CREATE_CASES = [
    (None, {}, 401),
    ("student1", {}, 201),
    ("student1", {"kind": "class", "course_id": "course"}, 403),
    ("tutor1", {"kind": "class", "course_id": "course"}, 201),
    ("tutor2", {"kind": "class", "course_id": "course"}, 403),
    ("admin1", {"kind": "class", "course_id": "course"}, 201),
]


@pytest.mark.parametrize(("who", "extra", "expected"), CREATE_CASES)
def test_who_may_book_what(client_as, app, course_people, who, extra, expected) -> None:
    extra = {k: (course_people[v] if k == "course_id" else v) for k, v in extra.items()}
    status, body = api(client_as(who), "POST", "/api/bookings", slot(0, 30, **extra))
    assert status == expected, body
    assert len(booking_rows(app)) == (1 if expected == 201 else 0)


# Who may cancel student1's booking.
CANCEL_CASES = [(None, 401), ("student1", 200), ("student2", 403), ("tutor1", 200), ("tutor2", 403), ("admin1", 200)]


@pytest.mark.parametrize(("who", "expected"), CANCEL_CASES)
def test_who_may_cancel_a_students_booking(client_as, app, who, expected) -> None:
    status, body = api(client_as("student1"), "POST", "/api/bookings", slot())
    booking_id = body["booking"]["id"]
    status, body = api(client_as(who), "DELETE", f"/api/bookings/{booking_id}")
    assert status == expected, body
    cancelled = booking_rows(app)[0][3]
    assert (cancelled is not None) == (expected == 200)


@pytest.mark.parametrize("path", ["/api/bookings", "/api/robots/lab-1/bookings", "/api/robots/lab-1/chat"])
def test_reading_needs_a_login(client_as, path) -> None:
    assert api(client_as(None), "GET", path)[0] == 401


@pytest.mark.parametrize("path", ["/bookings", "/bookings.ics"])
def test_pages_send_anonymous_visitors_to_the_login(client_as, path) -> None:
    status, headers, _ = client_as(None).request("GET", path)
    assert status == 302 and "/login" in headers["Location"]


def test_an_unknown_robot_is_404_naming_robot_name(client_as) -> None:
    status, body = api(client_as("student1"), "GET", "/api/robots/nope/bookings")
    assert status == 404 and body["error"]["field"] == "robot_name"


def test_a_missing_booking_is_404(client_as) -> None:
    assert api(client_as("admin1"), "DELETE", "/api/bookings/999")[0] == 404


def test_the_allowance_is_enforced_over_http(client_as, app) -> None:
    student = client_as("student1")
    assert api(student, "POST", "/api/bookings", slot(0, 120))[0] == 201
    status, body = api(student, "POST", "/api/bookings", slot(3, 30))
    assert status == 409 and body["error"]["code"] == "allowance_exceeded"


def test_the_form_books_and_cancels_with_csrf(client_as, app) -> None:
    student = client_as("student1")
    token = student.csrf_token("/bookings?tz=UTC")
    form = {"csrf_token": token, "robot_name": "lab-1", "tz": "Europe/Madrid", "week": "",
            "duration_min": "60", "starts_at": iso(START)}
    status, headers, _ = student.request("POST", "/bookings", form)
    assert status == 303
    _, _, page = student.request("GET", headers["Location"])
    assert "Booked lab-1" in page and "data-booking-id" in page
    assert api(student, "GET", "/api/bookings")[1]["bookings"][0]["ends_at"] == iso(START + timedelta(hours=1))
    missing = dict(form, csrf_token="")
    assert student.request("POST", "/bookings", missing)[0] == 400
    assert len(booking_rows(app)) == 1


def test_the_ical_export_lists_my_bookings(client_as) -> None:
    student = client_as("student1")
    api(student, "POST", "/api/bookings", slot(0, 60))
    status, headers, body = student.request("GET", "/bookings.ics")
    assert status == 200 and headers["Content-Type"].startswith("text/calendar")
    assert body.count("BEGIN:VEVENT") == 1 and f"DTSTART:{START:%Y%m%dT%H%M%SZ}" in body
    assert "\r\n" in body
