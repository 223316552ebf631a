"""A tutor writes the course's survey over the API (live app, SQLite and PostgreSQL): students rate its statements,
the results chart them with their ends, a survey with no statements is refused naming the field, and once a
student has answered the statements no longer change."""

from __future__ import annotations

from tests.integration.bookings.conftest import api


def test_a_tutor_writes_the_survey_students_rate_it_and_it_is_fixed_once_answered(client_as,
                                                                                  course_people) -> None:
    course = course_people["course"]
    tutor, students = client_as("tutor1"), [client_as(f"student{n}") for n in (1, 2)]
    path = f"/api/courses/{course}/survey/statements"
    assert len(api(students[0], "GET", path)[1]["statements"]) == 7  # the fixed seven until one is written
    assert api(students[0], "PUT", path, {"statements": [{"text": "x"}]})[0] == 403
    status, body = api(tutor, "PUT", path, {"title": "After the lesson", "statements": []})
    assert status == 400 and body["error"]["field"] == "statements"
    status, body = api(tutor, "PUT", path, {"statements": [{"text": "<b>ok</b>", "low_label": "x" * 61}]})
    assert status == 400 and body["error"]["field"] == "statements" and "low_label" in body["error"]["message"]
    written = {"title": "After the lesson", "statements": [
        {"text": "Part 2 (the robot turns) helped me learn"},
        {"text": "Part 3 (the robot's sound) helped me learn", "low_label": "Not at all",
         "high_label": "A great deal"}]}
    status, body = api(tutor, "PUT", path, written)
    assert status == 200 and [s["key"] for s in body["statements"]] == ["s1", "s2"] and body["written"]
    assert api(students[0], "GET", path)[1]["title"] == "After the lesson"

    status, body = api(students[0], "POST", f"/api/courses/{course}/survey", {"s1": 4, "s2": 9})
    assert status == 400 and body["error"]["field"] == "s2"
    status, body = api(students[0], "POST", f"/api/courses/{course}/survey", {"objectives_clear": 4})
    assert status == 400 and body["error"]["field"] == "s1"
    for student, ratings in zip(students, ({"s1": 4, "s2": 5}, {"s1": 2, "s2": 5}), strict=True):
        assert api(student, "POST", f"/api/courses/{course}/survey", {"ratings": ratings})[0] == 201
    status, body = api(tutor, "PUT", path, written)
    assert status == 409 and body["error"]["code"] == "survey_answered" and body["error"]["field"] == "statements"
    assert api(tutor, "GET", f"/api/courses/{course}/survey/results")[1]["respondents"] == 2
