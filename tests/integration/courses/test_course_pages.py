"""Courses over HTTP: creation with field errors, CSV upload with its report, invitations through /join."""

from __future__ import annotations

import re
import uuid
from urllib.request import HTTPCookieProcessor, Request, build_opener

from tests.conftest import LabClient
from tests.integration.bookings.conftest import api


def _upload(client: LabClient, path: str, filename: str, data: bytes, token: str) -> tuple[int, str]:
    boundary = uuid.uuid4().hex
    body = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"csrf_token\"\r\n\r\n{token}\r\n"
            f"--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"{filename}\"\r\n"
            "Content-Type: text/csv\r\n\r\n").encode() + data + f"\r\n--{boundary}--\r\n".encode()
    opener = build_opener(HTTPCookieProcessor(client.cookies))
    request = Request(client.base_url + path, data=body, method="POST",
                      headers={"Content-Type": f"multipart/form-data; boundary={boundary}"})
    try:
        with opener.open(request, timeout=60) as response:
            return response.status, response.read().decode()
    except Exception as error:
        if hasattr(error, "code"):
            return error.code, error.read().decode()
        raise


def test_course_fields_out_of_range_are_shown_next_to_the_field(client_as, course_people, snapshot) -> None:
    tutor = client_as("tutor1")
    before = snapshot()
    token = tutor.csrf_token("/courses")
    status, _, page = tutor.request("POST", "/courses", {"code": "NEW", "title": "New", "turn_length_s": "5",
                                                         "csrf_token": token})
    assert status == 400
    assert re.search(r'data-error-for="turn_length_s">turn_length_s must be a whole number of seconds from 10', page)
    status, answer = api(tutor, "PATCH", f"/api/courses/{course_people['course']}", {"booking_allowance_min": 10081})
    assert status == 400 and answer["error"]["field"] == "booking_allowance_min"
    for hold in (4, 241, "soon", 2.5):
        status, answer = api(tutor, "PATCH", f"/api/courses/{course_people['course']}", {"graded_run_hold_min": hold})
        assert status == 400 and answer["error"]["field"] == "graded_run_hold_min", hold
    assert snapshot() == before
    status, answer = api(tutor, "PATCH", f"/api/courses/{course_people['course']}", {"graded_run_hold_min": 45})
    assert status == 200 and answer["course"]["graded_run_hold_min"] == 45, answer


def test_csv_upload_shows_the_report_once_with_a_download(client_as, course_people) -> None:
    tutor = client_as("tutor1")
    course = course_people["course"]
    token = tutor.csrf_token(f"/courses/{course}")
    data = "username\nfresh1\nstudent1\ntutor2\n\nno way\n".encode("utf-8-sig")
    status, page = _upload(tutor, f"/courses/{course}/members.csv", "class.csv", data, token)
    assert status == 200
    assert re.search(r'data-field="created-count">1<', page) and re.search(r'data-field="refused-count">4<', page)
    assert 'download="enrolment-report-ROB1.csv"' in page and "data:text/csv" in page
    _, _, again = tutor.request("GET", f"/courses/{course}")
    assert "csv-report" not in again and "fresh1" in again

    status, page = _upload(tutor, f"/courses/{course}/members.csv", "latin1.csv", "username\njosé\n".encode("latin-1"),
                           token)
    assert status == 400 and 'data-error-for="file"' in page and "not UTF-8" in page


def test_an_invitation_link_creates_an_enrolled_account_once(client_as, course_people) -> None:
    tutor = client_as("tutor1")
    status, answer = api(tutor, "POST", "/api/invitations", {"course_id": course_people["course"]})
    assert status == 201
    path = "/join/" + answer["url"].rsplit("/join/", 1)[1]
    guest = client_as(None)
    assert guest.request("GET", path)[0] == 200
    token = guest.csrf_token(path)
    status, _, page = guest.request("POST", path, {"username": "student1", "password": "long-enough-pw",
                                                   "password_again": "long-enough-pw", "csrf_token": token})
    assert status == 400 and "is taken" in page
    status, headers, _ = guest.request("POST", path, {"username": "joiner", "password": "long-enough-pw",
                                                      "password_again": "long-enough-pw", "csrf_token": token})
    assert status == 303 and headers["Location"].endswith("/lab")
    _, courses = api(guest, "GET", "/api/courses")
    assert [c["code"] for c in courses["courses"]] == ["ROB1"]
    status, _, page = client_as(None).request("GET", path)
    assert status == 410 and "already been used" in page
    status, _, page = client_as(None).request("GET", "/join/" + "A" * 43)
    assert status == 404 and "not valid" in page


def test_a_tutor_withdraws_a_pending_invitation_and_its_link_stops_working(client_as, course_people) -> None:
    tutor = client_as("tutor1")
    status, answer = api(tutor, "POST", "/api/invitations", {"course_id": course_people["course"]})
    assert status == 201
    path = "/join/" + answer["url"].rsplit("/join/", 1)[1]
    invitation_id = answer["id"]
    # Only the course's tutors and admins may withdraw it.
    status, refused = api(client_as("tutor2"), "DELETE", f"/api/invitations/{invitation_id}")
    assert status == 403 and refused["error"]["code"] == "forbidden"
    assert api(client_as("student1"), "DELETE", f"/api/invitations/{invitation_id}")[0] == 403
    assert api(tutor, "DELETE", "/api/invitations/999999")[0] == 404
    # From the course page, with its button.
    _, _, page = tutor.request("GET", f"/courses/{course_people['course']}")
    assert f"/invitations/{invitation_id}/revoke" in page
    token = tutor.csrf_token(f"/courses/{course_people['course']}")
    status, headers, _ = tutor.request("POST", f"/invitations/{invitation_id}/revoke", {
        "csrf_token": token, "back": f"/courses/{course_people['course']}"})
    assert status == 303 and headers["Location"].endswith(f"/courses/{course_people['course']}")
    _, _, page = tutor.request("GET", f"/courses/{course_people['course']}")
    assert "revoked" in page and f"/invitations/{invitation_id}/revoke" not in page
    status, _, page = client_as(None).request("GET", path)
    assert status == 410 and "withdrawn" in page
    guest = client_as(None)
    status, _, _ = guest.request("POST", path, {"username": "latecomer", "password": "long-enough-pw",
                                                "password_again": "long-enough-pw",
                                                "csrf_token": guest.csrf_token("/login")})
    assert status == 410
    status, again = api(tutor, "DELETE", f"/api/invitations/{invitation_id}")
    assert status == 409 and again["error"]["code"] == "invitation_not_pending"
    # An admin withdraws any pending one through the API.
    _, other = api(tutor, "POST", "/api/invitations", {"course_id": course_people["course"]})
    status, body = api(client_as("admin1"), "DELETE", f"/api/invitations/{other['id']}")
    assert status == 200 and body["invitation"]["status"] == "revoked"
