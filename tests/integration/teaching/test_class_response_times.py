"""A tutor reads each student's response times in the class view: what the student's console reported for their
class robot, kept in the database, ten students reporting at once (and one from two tabs at once)."""

from __future__ import annotations

import copy
from concurrent.futures import ThreadPoolExecutor

import pytest

from tests.integration.teaching.test_class_sessions import STUDENTS, _login, _wait_until_ready, class_lab
from tests.integration.teaching.test_practice_console_and_uploads import _api

__all__ = ["class_lab"]


def report(mean_ms: float) -> dict:
    """A console's figures, as lib/response-times.js reportOf sends them."""
    leg = {"min": mean_ms / 2, "mean": mean_ms, "max": mean_ms * 2, "jitter": mean_ms / 4}
    robot = {"min": 1.5, "mean": 3.25, "max": 9.0, "jitter": 1.0}
    return {"skill": {"count": 3, "total": leg, "client": leg, "robot": robot},
            "drive": {"count": 0, "total": dict.fromkeys(leg), "client": dict.fromkeys(leg),
                      "robot": dict.fromkeys(leg)},
            "delivery": {"sent": 3, "late": 0, "lost": 1}, "throughput_bps": 512.5}


HOSTILE = [
    ({"skill": None}, "skill"),
    ({"skill": {"count": -1}}, "skill.count"),
    ({"skill": {"count": True}}, "skill.count"),
    ({"skill": {"count": 3, "total": {"min": "fast"}}}, "skill.total.min"),
    ({"skill": {"count": 3, "total": {"min": -1}}}, "skill.total.min"),
    ({"skill": {"count": 3, "total": {"min": 1e300}}}, "skill.total.min"),
    ({"delivery": {"sent": 1.5}}, "delivery.sent"),
    ({"throughput_bps": "lots"}, "throughput_bps"),
]


def hostile(change: dict) -> dict:
    """A valid report with change merged into it one level deep."""
    body = copy.deepcopy(report(100.0))
    for key, value in change.items():
        body[key] = value if not isinstance(value, dict) or not isinstance(body.get(key), dict) \
            else {**body[key], **value}
    return body


def test_each_student_s_response_times_reach_the_tutor_s_class_view(class_lab) -> None:
    server, course_id = class_lab
    tutor = _login(server, "tutor1")
    status, opened = _api(tutor, "POST", f"/api/courses/{course_id}/class-session")
    assert status == 201, opened
    _wait_until_ready(tutor, course_id)
    students = {name: _login(server, name) for name in STUDENTS}
    assert all(seat["response_times"] is None for seat in _api(tutor, "GET",
                                                               f"/api/courses/{course_id}/class-session")[1]["seats"])

    def send(item: tuple[int, str]) -> tuple[int, dict]:
        index, name = item
        return _api(students[name], "PUT", f"/api/robots/practice-{name}/response-times", report(10.0 * (index + 1)))

    # Ten students at once, and s01 from a second tab at the same moment (one row per student and robot).
    second_tab = _login(server, "s01")
    with ThreadPoolExecutor(11) as pool:
        answers = list(pool.map(send, enumerate(STUDENTS)))
        answers.append(pool.submit(_api, second_tab, "PUT", "/api/robots/practice-s01/response-times",
                                   report(10.0)).result())
    assert all(status == 200 for status, _ in answers), answers

    # A report on a robot that is not the student's class robot is not shown for the class.
    assert _api(students["s02"], "PUT", "/api/robots/lab-1/response-times", report(999.0))[0] == 200
    status, state = _api(tutor, "GET", f"/api/courses/{course_id}/class-session")
    assert status == 200
    shown = {seat["username"]: seat["response_times"] for seat in state["seats"]}
    for index, name in enumerate(STUDENTS):
        assert shown[name] == report(10.0 * (index + 1)), name

    # Someone else's robot is answered like a missing one; hostile figures are refused naming the field.
    status, error = _api(students["s02"], "PUT", "/api/robots/practice-s01/response-times", report(1.0))
    assert (status, error["error"]["code"]) == (404, "unknown_robot")
    for change, field in HOSTILE:
        status, error = _api(students["s03"], "PUT", "/api/robots/practice-s03/response-times", hostile(change))
        assert (status, error["error"]["field"]) == (400, field), (change, error)
    status, state = _api(tutor, "GET", f"/api/courses/{course_id}/class-session")
    assert {seat["username"]: seat["response_times"] for seat in state["seats"]} == shown
    _api(tutor, "DELETE", f"/api/courses/{course_id}/class-session")


@pytest.mark.parametrize("body", ["not json", [1, 2], None])
def test_a_report_that_is_not_an_object_is_refused(class_lab, body) -> None:
    server, _course_id = class_lab
    student = _login(server, "s01")
    status, error = _api(student, "PUT", "/api/robots/lab-1/response-times", body)
    assert (status, error["error"]["field"]) == (400, "body"), error
