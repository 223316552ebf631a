"""The "mark the obstacle zone" experimental test end to end on the real skill server: the tutor saves it (its truth
is read from the robot's scene then), the student never receives the truth before grading, saves rectangles as the
answer and is graded on them at submission; a malformed zone is refused naming the field."""

from __future__ import annotations

import json
from datetime import UTC, datetime, timedelta

from tests.integration.bookings.conftest import api
from tests.integration.lab.test_robot_channels import receive_json

TRUE_ZONE = [[2.2, 1.1, 2.8, 1.7], [-2.6, 1.35, -1.8, 1.85], [-1.6, -2.25, -0.4, -1.75], [1.55, -1.75, 2.05, -1.25]]


def test_the_zone_test_keeps_its_truth_from_the_student_and_grades_the_marks(app, client_as, course_people) -> None:
    now = datetime.now(UTC)
    tutor = client_as("tutor1")
    status, answer = api(tutor, "POST", f"/api/courses/{course_people['course']}/exams", {
        "title": "Find the obstacles", "kind": "experimental", "opens_at": (now - timedelta(minutes=1)).isoformat(),
        "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": 900, "task_kind": "obstacle_zone",
        "task_points": 10, "robot_name": "lab-1"})
    assert status == 201, answer
    exam_id = answer["exam"]["id"]
    assert answer["exam"]["task"]["rubric"] == [[0.5, 1.0], [0.7, 0.5], [0.85, 0.25]]

    student = client_as("student1")
    drive = student.websocket("/ws/robots/lab-1/drive")
    assert receive_json(drive)["type"] == "ready"
    try:
        status, answer = api(student, "POST", f"/api/exams/{exam_id}/attempts")
        assert status == 201, answer
        attempt = answer["attempt"]
        assert "zone" in attempt["items"]
        for status, seen in (api(student, "GET", f"/api/attempts/{attempt['id']}"),
                             api(student, "GET", f"/api/courses/{course_people['course']}/exams")):
            text = json.dumps(seen)
            leaked = [word for word in ('"obstacles"', '"bounds"', "center_x_m", "cabinet") if word in text]
            assert status == 200 and not leaked, leaked

        status, refused = api(student, "PATCH", f"/api/attempts/{attempt['id']}/answers",
                              {"answers": {"zone": {"rects": [[0, 0, 1, "x"]]}}})
        assert status == 400 and refused["error"]["field"] == "zone.rects[0]", refused
        status, saved = api(student, "PATCH", f"/api/attempts/{attempt['id']}/answers",
                            {"answers": {"zone": {"rects": TRUE_ZONE}}})
        assert status == 200, saved
        status, answer = api(student, "POST", f"/api/attempts/{attempt['id']}/submit")
        assert status == 200, answer
    finally:
        drive.close()
    task = next(r for r in answer["attempt"]["results"] if r["item"] == "task")
    assert task["points"] == 10 and task["correct"] and "IoU" in task["feedback"], task
