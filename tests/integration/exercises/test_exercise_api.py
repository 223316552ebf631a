"""The exercises API over HTTP on a real skill server: the server places the robot (a hidden start for a
submission), grades the run from the robot's own pose log, refuses a forged grade or trace, keeps a student's
code from another user's robot, shows a run only to its owner and their tutors, and lets tutors extend the
catalogue."""

from __future__ import annotations

import time

import pytest

from tests.integration.plans.conftest import PlansLab, api

STILL = "from telelab import robot\nwhile robot.tick():\n    robot.stop()\n"
NEW_EXERCISE = {"slug": "reach-the-crate", "title": "Reach the crate", "statement": "Drive to the crate.",
                "template": STILL, "scene": "lab", "start": [0, 0, 0],
                "random_starts": {"x_m": [-0.5, 0.5], "y_m": [-0.5, 0.5], "theta_rad": [-1, 1]},
                "rubric": {"kind": "reach_goal", "x_m": 2.0, "y_m": 1.4, "radius_m": 0.4}, "time_limit_s": 30}


def graded_run_open(lab: PlansLab, robot_name: str, username: str) -> bool:
    """Whether the access rules count username's run on robot_name as a graded one now (the truth hidden), read
    fresh and as the sockets' shared read of every open run sees it."""
    from datetime import UTC, datetime

    from sqlalchemy import select

    from middleware.access.graded_runs import graded_run_started_at, open_graded_runs
    from middleware.db import session_factory
    from middleware.models import User

    with lab.server.app.app_context(), session_factory(lab.server.app)() as session:
        user_id = session.scalar(select(User.id).where(User.username == username))
        now = datetime.now(UTC)
        fresh = graded_run_started_at(session, robot_name, user_id, now) is not None
        assert ((robot_name, user_id) in open_graded_runs(session, now)) == fresh  # the sockets' once-a-second read
        return fresh


def wait_for_practice_robot(client) -> None:
    status, answer = api(client, "POST", "/api/practice", {})
    assert status in (200, 202), answer
    deadline = time.monotonic() + 90
    while not answer.get("running"):
        assert time.monotonic() < deadline, "the practice robot did not start"
        time.sleep(0.5)
        _, answer = api(client, "GET", "/api/practice")


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_runs_are_placed_and_graded_by_the_server_and_seen_by_owner_and_tutor_only(plans_lab: PlansLab) -> None:
    ann = plans_lab.client("student1")
    # Nothing a request sends can stand for the robot's record.
    for forged in ("grade", "trace", "start", "measurements"):
        status, answer = api(ann, "POST", "/api/exercises/bump-and-go/runs", {"code": STILL, forged: 1})
        assert (status, answer["error"]["field"]) == (400, forged), answer
    # Another user's robot is answered like a missing one; a lab robot needs the turn.
    status, answer = api(ann, "POST", "/api/exercises/bump-and-go/runs", {"code": STILL, "robot": "practice-student2"})
    assert (status, answer["error"]["code"]) == (404, "unknown_robot"), answer
    status, answer = api(ann, "POST", "/api/exercises/bump-and-go/runs", {"code": STILL, "robot": "lab-1"})
    assert (status, answer["error"]["code"]) == (403, "not_controller"), answer

    wait_for_practice_robot(ann)
    status, answer = api(ann, "POST", "/api/exercises/bump-and-go/runs", {"code": STILL, "mode": "practice"})
    assert status == 201, answer
    practice = answer["run"]
    assert practice["start"] == [0.0, 0.0, 0.0] and practice["robot_name"] == "practice-student1"
    time.sleep(1.5)  # a few pose-log samples
    status, answer = api(ann, "POST", f"/api/exercise-runs/{practice['id']}/finish", {"trace": [[0, 9, 9]]})
    assert (status, answer["error"]["field"]) == (400, "trace"), answer
    status, answer = api(ann, "POST", f"/api/exercise-runs/{practice['id']}/finish", {})
    assert status == 200, answer
    graded = answer["run"]
    assert graded["status"] == "graded" and len(graded["trace"]) >= 3
    driven = next(m for m in graded["measurements"] if m["name"] == "distance driven")
    assert driven["value"] < 0.05 and graded["grade"] < 0.5  # it stood still: the truth says so
    assert answer["scene_boxes"]

    # The course's tutor attaches the exercise as a test; another course's tutor and a student cannot.
    test = {"slug": "bump-and-go", "deadline_at": "2100-01-01T12:00:00Z", "points": 10}
    for name, expected in (("student1", 403), ("tutor2", 403), ("tutor1", 201)):
        status, answer = api(plans_lab.client(name), "POST", f"/api/courses/{plans_lab.course}/exercises", test)
        assert status == expected, (name, answer)
    status, answer = api(plans_lab.client("tutor1"), "POST", f"/api/courses/{plans_lab.course}/exercises",
                         {**test, "deadline_at": "tomorrow"})
    assert (status, answer["error"]["field"]) == (400, "deadline_at")

    status, answer = api(ann, "POST", "/api/exercises/bump-and-go/runs", {"code": STILL, "mode": "submission"})
    assert status == 201, answer
    submission = answer["run"]
    assert submission["start"] is None  # hidden until the run is over
    assert graded_run_open(plans_lab, "practice-student1", "student1")  # its streams carry no truth meanwhile
    _, answer = api(ann, "POST", f"/api/exercise-runs/{submission['id']}/finish", {})
    assert not graded_run_open(plans_lab, "practice-student1", "student1")
    assert answer["run"]["start"] is not None and answer["run"]["start"] != [0.0, 0.0, 0.0]
    submitted = answer["run"]["grade"]
    _, answer = api(ann, "GET", "/api/exercises/bump-and-go")
    assert answer["tests"] == [{"course_id": plans_lab.course, "course": "Course ROB1",
                                "deadline_at": "2100-01-01T12:00:00+00:00", "points": 10.0,
                                "mark": round(submitted * 10, 2), "leaderboard_open": False}]
    status, page = api(ann, "GET", "/exercises/bump-and-go")
    assert status == 200 and "A test of Course ROB1: submit before 2100-01-01 12:00 UTC (10.0 points)" in page["body"]
    assert page["headers"]["Cross-Origin-Embedder-Policy"] == "require-corp"
    status, worker = api(ann, "GET", "/exercises/python-worker.js")
    assert "'wasm-unsafe-eval'" in worker["headers"]["Content-Security-Policy"]
    assert "'wasm-unsafe-eval'" not in page["headers"]["Content-Security-Policy"]

    # The owner and their tutor read a run; another student and another course's tutor get a 404.
    for name, expected in (("student1", 200), ("tutor1", 200), ("student2", 404), ("tutor2", 404)):
        status, _ = api(plans_lab.client(name), "GET", f"/api/exercise-runs/{practice['id']}")
        assert status == expected, name
    status, answer = api(plans_lab.client("tutor1"), "GET", "/api/exercises/bump-and-go/class")
    assert status == 200
    row = next(r for r in answer["students"] if r["username"] == "student1")
    assert row["codes"][0]["code"] == STILL and len(row["runs"]) == 2
    assert not any(r["username"] == "student3" for r in answer["students"])
    status, _ = api(ann, "GET", "/api/exercises/bump-and-go/class")
    assert status == 403
    status, page = api(plans_lab.client("tutor1"), "GET", "/exercises/bump-and-go/class")
    assert status == 200 and 'data-student="student1"' in page["body"] and "robot.stop()" in page["body"]


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_tutors_extend_the_catalogue_and_students_cannot(plans_lab: PlansLab) -> None:
    status, answer = api(plans_lab.client("student1"), "POST", "/api/exercises", NEW_EXERCISE)
    assert status == 403, answer
    tutor = plans_lab.client("tutor1")
    status, answer = api(tutor, "POST", "/api/exercises", {**NEW_EXERCISE, "rubric": {"kind": "teleport"}})
    assert (status, answer["error"]["field"]) == (400, "rubric.kind"), answer
    status, answer = api(tutor, "POST", "/api/exercises", {**NEW_EXERCISE, "time_limit_s": 1e9})
    assert (status, answer["error"]["field"]) == (400, "time_limit_s"), answer
    status, answer = api(tutor, "POST", "/api/exercises", NEW_EXERCISE)
    assert status == 201, answer
    assert "random_starts" not in answer["exercise"]  # the hidden starts stay the server's
    status, answer = api(tutor, "POST", "/api/exercises", NEW_EXERCISE)
    assert (status, answer["error"]["code"]) == (409, "slug_taken")
    status, answer = api(plans_lab.client("student1"), "GET", "/api/exercises")
    assert "reach-the-crate" in [e["slug"] for e in answer["exercises"]]
