"""An experimental test on the real skill server: the student in control drives, the run is recorded (ground truth
included) and graded at submission; a student without control cannot start it. The robot's start pose depends on
earlier tests sharing the skill server, so the mark is checked against the recorded run, not a fixed number.
"""

from __future__ import annotations

import math
import time
from datetime import UTC, datetime, timedelta

from tests.integration.bookings.conftest import api
from tests.integration.lab.test_robot_channels import drive_for, receive_json


def test_a_driven_run_is_recorded_and_graded_at_submission(app, client_as, course_people) -> None:
    from middleware.assessment import bank
    from middleware.assessment.schemas import parse_exam
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.assessment import Attempt

    now = datetime.now(UTC)
    with session_factory(app)() as session:
        tutor = session.get(User, course_people["tutor1"])
        exam = bank.create_exam(session, tutor, course_people["course"], parse_exam({
            "title": "Drive to the point", "kind": "experimental", "opens_at": (now - timedelta(minutes=1)).isoformat(),
            "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": 600, "task_kind": "reach_point",
            "x_m": 0.0, "y_m": 0.0, "rubric": "0.1:1, 0.5:0.5, 2:0.25", "task_points": 10, "robot_name": "lab-1"}))
        session.commit()
        exam_id = exam.id
    student = client_as("student1")
    drive = student.websocket("/ws/robots/lab-1/drive")
    assert receive_json(drive)["type"] == "ready"
    other = client_as("student2")
    status, answer = api(other, "POST", f"/api/exams/{exam_id}/attempts")
    assert status == 409 and answer["error"]["code"] == "no_robot"

    status, answer = api(student, "POST", f"/api/exams/{exam_id}/attempts")
    assert status == 201, answer
    attempt_id = answer["attempt"]["id"]
    time.sleep(0.5)
    drive_for(drive, 1.5, 0.2, 0.0, 1)
    time.sleep(0.5)
    status, answer = api(student, "POST", f"/api/attempts/{attempt_id}/submit")
    drive.close()
    assert status == 200, answer
    task = next(r for r in answer["attempt"]["results"] if r["item"] == "task")
    assert "trace" not in answer["attempt"]
    with session_factory(app)() as session:
        trace = session.get(Attempt, attempt_id).trace
    assert trace and len(trace) >= 5
    travelled = math.hypot(trace[-1][1] - trace[0][1], trace[-1][2] - trace[0][2])
    assert travelled > 0.05, "the recorded ground truth shows the robot moving"
    error = math.hypot(trace[-1][1], trace[-1][2])
    expected = 10 if error <= 0.1 else 5 if error <= 0.5 else 2.5 if error <= 2 else 0
    assert task["points"] == expected and f"{error:.3f} m" in task["feedback"]
