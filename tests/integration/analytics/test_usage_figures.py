"""The usage figures from a seeded week equal the ones worked out by hand (conftest.history), on SQLite and
PostgreSQL; who may read them (a student nobody's, a tutor their courses' only); hostile query parameters refused
with an error naming the parameter."""

from __future__ import annotations

import csv
import io
import json
from urllib.parse import urlencode

import pytest

from tests.integration.analytics.conftest import WINDOW, at
from tests.integration.bookings.conftest import api


def usage(client, **query) -> tuple[int, dict]:
    return api(client, "GET", "/api/analytics/usage?" + urlencode({**WINDOW, **query}))


def test_a_courses_figures_equal_those_worked_out_by_hand(lab, client_of) -> None:
    _server, ids = lab
    status, data = usage(client_of("ta"), course_id=ids["A"])
    assert status == 200, data
    assert (data["window"]["start"], data["window"]["end"]) == ("2026-03-01T23:00:00+00:00",
                                                                "2026-03-08T23:00:00+00:00")
    assert [s["id"] for s in data["sessions"]] == [ids["r3"], ids["r2"], ids["r1"]], "newest first, the course's only"
    first = data["sessions"][-1]
    assert (first["username"], first["robot_name"], first["duration_s"], first["command_count"], first["skill_count"],
            first["plan_count"], first["end_reason"]) == ("s1", "lab-1", 2700.0, 12, 2, 1, "turn_ended")
    assert data["students"] == [{"user_id": ids["s1"], "username": "s1", "sessions": 2, "seconds": 8100.0},
                                {"user_id": ids["s2"], "username": "s2", "sessions": 1, "seconds": 1800.0}]
    expected = [[0.0] * 24 for _ in range(7)]
    expected[0][10], expected[0][11], expected[2][23], expected[3][0], expected[3][1], expected[6][23] = (
        30.0, 15.0, 10.0, 60.0, 20.0, 30.0)
    assert data["heat_map"] == expected
    waits = data["waits"]
    assert (waits["count"], waits["mean_s"], waits["median_s"], waits["p90_s"], waits["max_s"]) == (
        5, 191.0, 45.0, 700.0, 700.0)
    assert [b["count"] for b in waits["bins"]] == [1, 1, 1, 0, 1, 0, 1, 0]
    robots = {r["robot_name"]: r for r in data["robots"]}
    assert "practice-s2" not in robots, "a practice robot is nobody's lab robot"
    lab_1 = robots["lab-1"]
    assert (lab_1["sessions"], lab_1["seconds_used"], lab_1["outages"], lab_1["downtime_s"], lab_1["uptime_pct"],
            lab_1["maintenance"]) == (2, 8100.0, 2, 5400.0, 99.11, {"restart": 1, "dock": 1})
    ghost = robots["ghost2"]
    assert (ghost["outages"], ghost["downtime_s"], ghost["uptime_pct"]) == (1, 3600.0, 99.4)
    assert "xapi" not in data, "the outbox's state is the admins'"


def test_an_admin_reads_every_course_and_a_tutor_without_a_course_reads_all_of_theirs(lab, client_of) -> None:
    _server, ids = lab
    status, everyone = usage(client_of("ad"))
    assert status == 200
    assert {s["id"] for s in everyone["sessions"]} == {ids["r1"], ids["r2"], ids["r3"], ids["r5"]}
    assert everyone["waits"]["count"] == 6 and everyone["waits"]["max_s"] == 5000.0
    assert everyone["xapi"]["lrs"] is False
    status, mine = usage(client_of("ta"))
    assert status == 200 and {s["id"] for s in mine["sessions"]} == {ids["r1"], ids["r2"], ids["r3"]}
    status, theirs = usage(client_of("tb"))
    assert status == 200 and [s["id"] for s in theirs["sessions"]] == [ids["r5"]]


@pytest.mark.parametrize("who, course, status, code", [
    ("s1", "A", 403, "forbidden"), ("s1", None, 403, "forbidden"), ("tb", "A", 403, "forbidden"),
    ("ta", "B", 403, "forbidden"), ("ta", "missing", 404, "unknown_course")])
def test_a_student_reads_nothing_and_a_tutor_only_their_courses(lab, client_of, who, course, status, code) -> None:
    _server, ids = lab
    query = {} if course is None else {"course_id": ids.get(course, 987654)}
    answer_status, answer = usage(client_of(who), **query)
    assert (answer_status, answer["error"]["code"]) == (status, code), answer
    if course is not None:
        assert answer["error"]["field"] == (None if who.startswith("s") else "course_id"), answer
        for path in (f"/api/analytics/students.csv?course_id={query['course_id']}",
                     f"/api/analytics/courses/{query['course_id']}/xapi"):
            assert api(client_of(who), "GET", path)[0] == status, path
    page_status, _headers, _body = client_of(who).request("GET", "/analytics")
    assert page_status == (403 if who.startswith("s") else 200)


@pytest.mark.parametrize("query, field", [
    ({"from": "2026-13-01"}, "from"), ({"to": "yesterday"}, "to"), ({"from": "0001-01-01"}, "from"),
    ({"from": "2026-03-09", "to": "2026-03-01"}, "from"), ({"from": "2024-01-01", "to": "2026-03-01"}, "from"),
    ({"to": "2026-03-08\u0663"}, "to"), ({"utc_offset_min": "9999"}, "utc_offset_min"),
    ({"utc_offset_min": "1e3"}, "utc_offset_min"), ({"course_id": "-1"}, "course_id"),
    ({"course_id": "99999999999999999999999"}, "course_id"), ({"course_id": "1 OR 1=1"}, "course_id"),
    ({"course_id": "\u00b2"}, "course_id")])
def test_hostile_parameters_are_refused_naming_the_parameter(lab, client_of, query, field) -> None:
    for path in ("/api/analytics/usage", "/api/analytics/sessions.csv"):
        status, answer = api(client_of("ad"), "GET", f"{path}?{urlencode(query)}")
        assert (status, answer["error"]["code"], answer["error"]["field"]) == (400, "invalid_field", field), answer


def test_an_unknown_report_is_refused_naming_it(lab, client_of) -> None:
    status, answer = api(client_of("ad"), "GET", "/api/analytics/passwords.csv")
    assert (status, answer["error"]["field"]) == (400, "report")


def test_each_csv_holds_the_figures_of_the_page(lab, client_of) -> None:
    _server, ids = lab
    query = urlencode({**WINDOW, "course_id": ids["A"]})

    def rows(report: str) -> list[list[str]]:
        status, headers, body = client_of("ta").request("GET", f"/api/analytics/{report}.csv?{query}")
        assert status == 200 and "text/csv" in headers.get("Content-Type", ""), (report, status)
        return list(csv.reader(io.StringIO(body)))

    assert rows("students")[1:] == [["s1", "2", "8100.0"], ["s2", "1", "1800.0"]]
    sessions = rows("sessions")
    assert sessions[0][:3] == ["session_id", "username", "robot"] and len(sessions) == 4
    heat = rows("heatmap")
    assert heat[1][0] == "monday" and heat[1][1 + 10] == "30.0" and heat[4][1 + 0] == "60.0"
    assert sorted(float(r[4]) for r in rows("waits")[1:]) == [0.0, 10.0, 45.0, 200.0, 700.0]
    lab_row = next(r for r in rows("robots") if r[0] == "lab-1")
    assert lab_row[1:] == ["2", "8100.0", "2", "5400.0", "99.11", "dock=1 restart=1"]


def test_a_courses_xapi_statements_are_its_students_and_valid_xapi_1_0_3(lab, client_of) -> None:
    from middleware.analytics.xapi_schema import statement_errors

    _server, ids = lab
    status, _headers, body = client_of("ta").request(
        "GET", f"/api/analytics/courses/{ids['A']}/xapi?{urlencode(WINDOW)}")
    assert status == 200
    document = json.loads(body)
    statements = document["statements"]
    # s1's lesson, s2's tour, s1's test of course A (not s3's of B), s2's exercise, and the sessions of A's students
    # that ended within the window (r1, r2: r3 ended after it, r4 before).
    verbs = sorted((s["verb"]["display"]["en"], s["object"]["definition"]["name"]["en"]) for s in statements)
    assert verbs == [("attended", "lab-1"), ("attended", "lab-1"), ("completed", "Sonar tour"),
                     ("submitted", "Bump and go"), ("submitted", "Test A"), ("watched", "Odometry lesson")]
    for statement in statements:
        assert statement_errors(statement) == [], statement
    test = next(s for s in statements if s["object"]["definition"]["name"]["en"] == "Test A")
    assert test["result"]["score"] == {"raw": 3.0, "min": 0.0, "max": 4.0, "scaled": 0.75}
    assert test["result"]["duration"] == "PT1200.0S"
    assert test["actor"]["account"]["name"] == str(ids["s1"])
    assert len({s["id"] for s in statements}) == len(statements)
    status, _headers, again = client_of("ad").request(
        "GET", f"/api/analytics/courses/{ids['A']}/xapi?{urlencode(WINDOW)}")
    assert [s["id"] for s in json.loads(again)["statements"]] == [s["id"] for s in statements], (
        "the same events are the same statements, whoever exports them")


def test_a_lesson_watched_and_a_tour_followed_are_recorded_once_a_minute(lab, client_of) -> None:
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models.analytics import LearningEvent

    server, ids = lab
    student = client_of("s2")
    assert api(student, "POST", f"/api/lessons/{ids['lesson']}/watched") == (200, {"recorded": True})
    assert api(student, "POST", f"/api/lessons/{ids['lesson']}/watched") == (200, {"recorded": False})
    assert api(student, "POST", f"/api/tours/{ids['tour']}/followed") == (200, {"recorded": True})
    assert api(student, "POST", "/api/lessons/987654/watched")[0] == 404
    assert api(student, "POST", "/api/tours/987654/followed")[0] == 404
    with session_factory(server.app)() as session:
        kinds = sorted(session.scalars(select(LearningEvent.kind).where(LearningEvent.user_id == ids["s2"],
                                                                        LearningEvent.at > at(20, 0))))
    assert kinds == ["lesson_watched", "tour_followed"]
