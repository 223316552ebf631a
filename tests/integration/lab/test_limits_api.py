"""The low-level commands API through the middleware against the real skill server: who may read and change the
velocity ceilings and the watchdog (role, course setting, control), errors naming the field, battery telemetry."""

from __future__ import annotations

import json

import pytest

from tests.conftest import LabClient, LiveServer, make_course
from tests.integration.lab.test_skills_api import api, take_control, tutor

LIMITS = "/api/robots/lab-1/limits"


def set_course(live_server: LiveServer, course_id: int, **flags: bool) -> None:
    from middleware.db import session_factory
    from middleware.models import Course

    with session_factory(live_server.app)() as session:
        course = session.get(Course, course_id)
        for name, value in flags.items():
            setattr(course, name, value)
        session.commit()


def test_an_observer_reads_the_limits_and_may_not_change_them(student_client: LabClient) -> None:
    status, body = api(student_client, "GET", LIMITS)
    assert status == 200, body
    assert body["limits"]["robot_max_linear_mps"] == 0.5 and body["limits"]["max_watchdog_s"] == 5.0
    assert body["may_change"] == ["max_linear_mps", "max_angular_radps"], "a student in no course: the defaults"
    status, body = api(student_client, "POST", LIMITS, {"max_linear_mps": 0.3})
    assert status == 403 and body["error"]["code"] == "not_controller", body


def test_the_controller_changes_what_the_course_allows_and_hears_the_field_at_fault(
        live_server: LiveServer, student_client: LabClient) -> None:
    queue = take_control(student_client)
    status, body = api(student_client, "POST", LIMITS, {"max_linear_mps": 0.3, "max_angular_radps": 0})
    assert status == 200, body
    assert body["limits"]["max_linear_mps"] == 0.3 and body["limits"]["max_angular_radps"] == 1.5
    assert "max_linear_mps" in body["message"]
    assert api(student_client, "GET", LIMITS)[1]["limits"]["max_linear_mps"] == 0.3

    status, body = api(student_client, "POST", LIMITS, {"watchdog_s": 1.0})
    assert (status, body["error"]["code"], body["error"]["field"]) == (403, "not_permitted", "watchdog_s"), body
    status, body = api(student_client, "POST", LIMITS, {"max_linear_mps": 0.9})
    assert (status, body["error"]["field"]) == (400, "max_linear_mps"), body
    assert "0.5" in body["error"]["message"], "the robot's own ceiling is named"
    assert api(student_client, "GET", LIMITS)[1]["limits"]["max_linear_mps"] == 0.3, "a refusal changes nothing"

    course_id = make_course(live_server.app, "LOW1", {"student1": "student"})
    set_course(live_server, course_id, students_set_watchdog=True, students_set_velocity=False)
    status, body = api(student_client, "POST", LIMITS, {"watchdog_s": 1.0})
    assert status == 200 and body["limits"]["watchdog_s"] == 1.0, body
    assert body["may_change"] == ["watchdog_s"]
    status, body = api(student_client, "POST", LIMITS, {"max_angular_radps": 1.0})
    assert (status, body["error"]["code"], body["error"]["field"]) == (403, "not_permitted", "max_angular_radps")
    queue.close()


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"max_linear_mps": "fast"}, "max_linear_mps"),
        ({"max_linear_mps": True}, "max_linear_mps"),
        ({"max_angular_radps": -1}, "max_angular_radps"),
        ({"watchdog_s": 1e400}, "watchdog_s"),
        ({"speed": 0.2}, "speed"),
        ({}, "body"),
        ({"max_linear_mps": 0}, "body"),
        ([0.2], "body"),
    ],
)
def test_malformed_requests_are_400_naming_the_field(student_client: LabClient, body: object, field: str) -> None:
    status, answer = api(student_client, "POST", LIMITS, body)
    assert (status, answer["error"]["code"], answer["error"]["field"]) == (400, "invalid_field", field), answer


def test_a_tutor_in_control_changes_every_setting(live_server: LiveServer) -> None:
    teacher = tutor(live_server, "limits-tutor")
    queue = take_control(teacher)
    status, body = api(teacher, "GET", LIMITS)
    assert body["may_change"] == ["max_linear_mps", "max_angular_radps", "watchdog_s"]
    status, body = api(teacher, "POST", LIMITS, {"max_linear_mps": 0.25, "max_angular_radps": 0.8, "watchdog_s": 2})
    assert status == 200, body
    assert (body["limits"]["max_linear_mps"], body["limits"]["max_angular_radps"], body["limits"]["watchdog_s"]) == (
        0.25, 0.8, 2.0)
    queue.close()


def test_the_tutor_sets_what_a_course_s_students_may_change(live_server: LiveServer) -> None:
    teacher = tutor(live_server, "course-limits-tutor")
    course_id = make_course(live_server.app, "LOW2", {"course-limits-tutor": "tutor"})
    status, body = api(teacher, "GET", f"/api/courses/{course_id}")
    assert (body["course"]["students_set_velocity"], body["course"]["students_set_watchdog"]) == (True, False)
    status, body = api(teacher, "PATCH", f"/api/courses/{course_id}", {"students_set_watchdog": True})
    assert status == 200 and body["course"]["students_set_watchdog"] is True, body
    status, body = api(teacher, "PATCH", f"/api/courses/{course_id}", {"students_set_velocity": "maybe"})
    assert (status, body["error"]["field"]) == (400, "students_set_velocity"), body


def test_telemetry_carries_the_battery(student_client: LabClient) -> None:
    telemetry = student_client.websocket("/ws/robots/lab-1/telemetry")
    for _ in range(20):
        message = json.loads(telemetry.receive(timeout=5))
        if message["type"] == "telemetry":
            battery = message["battery"]
            assert set(battery) == {"charge", "charging", "empty"} and 0.0 <= battery["charge"] <= 1.0
            return
    raise AssertionError("no telemetry message")


def test_the_course_page_offers_the_setting_and_saves_it(live_server: LiveServer) -> None:
    teacher = tutor(live_server, "form-limits-tutor")
    course_id = make_course(live_server.app, "LOW3", {"form-limits-tutor": "tutor"})
    _, _, page = teacher.request("GET", f"/courses/{course_id}")
    assert 'name="students_set_watchdog"' in page and 'name="students_set_velocity"' in page
    token = teacher.csrf_token(f"/courses/{course_id}")
    status, _, _ = teacher.request("POST", f"/courses/{course_id}/settings", {
        "csrf_token": token, "title": "Course LOW3", "students_set_velocity": "no", "students_set_watchdog": "yes"})
    assert status == 303
    status, body = api(teacher, "GET", f"/api/courses/{course_id}")
    assert (body["course"]["students_set_velocity"], body["course"]["students_set_watchdog"]) == (False, True)
