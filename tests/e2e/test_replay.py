"""The replay page in Chromium: a recording (written by the recorder's own part writer, with lab-1's real scene
and a known track) opens with its command log; scrubbing the timeline to a time shows the pose the file holds for
that time; the student's page carries no truth; desktop and phone screenshots are kept."""

from __future__ import annotations

import math
from datetime import UTC, datetime

from middleware.recordings import channels, files
from protos.telelab.v1 import robot_pb2
from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer

START_UNIX_S = 1_800_000_000.0
RATE_HZ = 10


def track_pose(t: float) -> tuple[float, float, float]:
    """The recorded robot's pose t seconds in: a slow arc."""
    return 0.2 * t, 0.5 * math.sin(0.3 * t), 0.15 * math.cos(0.3 * t)


def write_recording(app, skill_server_address: str, kind: str = "turn",
                    ref_id: int | None = None) -> tuple[int, list[tuple[float, float, float, float]]]:
    """A 20-second recording of student1 on lab-1 (odometry, truth, sonar, commands, a goal); its id and track."""
    import grpc

    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.recordings import Recording
    from middleware.recordings.parts import recordings_of
    from protos.telelab.v1 import robot_pb2_grpc

    with grpc.insecure_channel(skill_server_address) as channel:
        stub = robot_pb2_grpc.RobotStub(channel)
        scene = stub.GetScene(robot_pb2.GetSceneRequest(), timeout=10)
        info = stub.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=10)
    with session_factory(app)() as session:
        user = session.query(User).filter_by(username="student1").one()
        recording = Recording(user_id=user.id, robot_name="lab-1", kind=kind, ref_id=ref_id, explicit=False,
                              started_at=datetime.fromtimestamp(START_UNIX_S, UTC),
                              ended_at=datetime.fromtimestamp(START_UNIX_S + 20, UTC), end_reason="turn_ended",
                              status="ready", command_count=3)
        session.add(recording)
        session.commit()
        recording_id = recording.id
    root = recordings_of(app).settings.directory
    writer = files.PartWriter(files.new_part_path(root, recording_id, "test"), {"robot": "lab-1"})
    ns = lambda t: int((START_UNIX_S + t) * 1e9)  # noqa: E731
    writer.write(channels.ROBOT_INFO, info, ns(0))
    writer.write(channels.SCENE, scene, ns(0))
    track = []
    for i in range(20 * RATE_HZ + 1):
        t = i / RATE_HZ
        x, y, th = track_pose(t)
        track.append((t, x, y, th))
        pose = robot_pb2.Pose2D(x_m=x, y_m=y, theta_rad=th)
        writer.write(channels.ODOMETRY, robot_pb2.Odometry(pose=pose, linear_mps=0.2, angular_radps=0.05), ns(t))
        writer.write(channels.GROUND_TRUTH, robot_pb2.Pose2D(x_m=x + 0.01, y_m=y, theta_rad=th), ns(t))
        writer.write(channels.SONAR, robot_pb2.SonarReading(ranges_m=[1.0 + 0.1 * k for k in range(8)]), ns(t))
    for k, t in enumerate((2.0, 9.5, 15.0)):
        writer.write(channels.COMMANDS, channels.CommandRecord(
            sent_unix_s=START_UNIX_S + t, sequence=k + 1, source="pad", action="drive", linear_mps=0.2,
            accepted=True), ns(t))
    writer.write(channels.GOALS, robot_pb2.GoalState(goal_id="g-1", skill="go_to_goal",
                                                     status=robot_pb2.GOAL_STATUS_SUCCEEDED), ns(12.0))
    writer.finish()
    return recording_id, track


def shown_pose(page) -> tuple[float, float, float]:
    pose = page.get_by_test_id("replay-pose")
    return float(pose.get_attribute("data-t")), float(pose.get_attribute("data-x")), float(pose.get_attribute("data-y"))


def test_scrubbing_the_replay_shows_the_pose_the_file_holds_for_that_time(
        page, app, live_server: LiveServer, skill_server_address: str) -> None:
    recording_id, track = write_recording(app, skill_server_address)
    page.goto(f"{live_server.url}/login")
    page.get_by_label("Username").fill("student1")
    page.get_by_label("Password").fill(STUDENT_PASSWORD)
    page.get_by_role("button", name="Log in").click()
    page.locator('[data-field="username"]').wait_for()
    page.goto(f"{live_server.url}/recordings")
    page.get_by_role("link", name="2027-01-15 08:00:00").click()
    page.locator("#replay[data-ready=true]").wait_for(timeout=20_000)
    assert page.locator('[data-slot="commands"] li').count() == 3
    assert "true pose" not in page.locator(".replay__legend").inner_text(), "a student sees no truth"

    slider = page.get_by_role("slider", name="Time")
    box = slider.bounding_box()
    assert box is not None
    for fraction in (0.25, 0.6, 0.9):
        page.mouse.click(box["x"] + box["width"] * fraction, box["y"] + box["height"] / 2)
        t, x, y = shown_pose(page)
        now = float(slider.input_value())
        expected = max(sample for sample in track if sample[0] <= now + 1e-9)
        assert abs(t - expected[0]) < 1e-6 and abs(x - expected[1]) < 1e-3 and abs(y - expected[2]) < 1e-3, (
            fraction, now, (t, x, y), expected)
        assert 0.1 < now / 20 < 1.0
        # The 3D view draws the robot there too, at its next frame (it draws at most so many a second).
        page.wait_for_function("""([x, y]) => {
          const drawn = document.querySelector('lab-view')?.dataset.drawnPose?.split(' ').map(Number);
          return drawn?.length === 3 && Math.abs(drawn[0] - x) < 1e-2 && Math.abs(drawn[1] - y) < 1e-2;
        }""", arg=[x, y], timeout=5_000)
    # The keyboard scrubs as well: End goes to the last sample.
    slider.focus()
    page.keyboard.press("End")
    t, x, y = shown_pose(page)
    assert abs(t - 20.0) < 1e-6 and abs(x - track[-1][1]) < 1e-3
    # A command in the log is a jump to its time.
    page.locator('[data-slot="commands"] button').nth(1).click()
    assert abs(float(slider.input_value()) - 9.5) < 0.06
    assert abs(shown_pose(page)[0] - 9.5) < 1e-6

    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "replay-desktop.png"), full_page=True)
    page.set_viewport_size({"width": 390, "height": 844})
    page.reload()
    page.locator("#replay[data-ready=true]").wait_for(timeout=20_000)
    width = page.evaluate("document.documentElement.scrollWidth")
    assert width <= 390, f"the replay page scrolls sideways on a phone ({width} px)"
    page.screenshot(path=str(ARTIFACTS_DIR / "replay-phone.png"), full_page=True)


def graded_attempt(app) -> int:
    """A submitted experimental attempt of student1 (reach_point at (4, 0.3), graded): its id."""
    from middleware.db import session_factory
    from middleware.models import Course, User
    from middleware.models.assessment import Attempt, Exam

    with session_factory(app)() as session:
        user = session.query(User).filter_by(username="student1").one()
        course = Course(code="REPLAY", title="Replay")
        session.add(course)
        session.flush()
        exam = Exam(course_id=course.id, title="Reach", kind="experimental", robot_name="lab-1", question_ids=[],
                    task={"kind": "reach_point", "x_m": 4.0, "y_m": 0.3, "points": 2.0})
        session.add(exam)
        session.flush()
        attempt = Attempt(exam_id=exam.id, user_id=user.id, status="submitted", started_at=datetime.now(UTC),
                          submitted_at=datetime.now(UTC), answers={},
                          results=[{"item": "task", "points": 1.0, "max_points": 2.0, "correct": False,
                                    "feedback": "The robot ended 0.081 m from (4.0, 0.3).", "topics": []}])
        session.add(attempt)
        session.commit()
        return attempt.id


def test_a_test_attempt_s_run_opens_from_its_id_with_what_the_rubric_measured(
        page, app, live_server: LiveServer, skill_server_address: str) -> None:
    attempt_id = graded_attempt(app)
    write_recording(app, skill_server_address, kind="test_attempt", ref_id=attempt_id)
    page.goto(f"{live_server.url}/login")
    page.get_by_label("Username").fill("student1")
    page.get_by_label("Password").fill(STUDENT_PASSWORD)
    page.get_by_role("button", name="Log in").click()
    page.locator('[data-field="username"]').wait_for()
    page.goto(f"{live_server.url}/recordings/of/test_attempt/{attempt_id}")
    page.locator("#replay[data-ready=true]").wait_for(timeout=20_000)
    measured = page.get_by_test_id("replay-measurement").inner_text()
    assert "1 of 2 points" in measured and "0.081 m" in measured, measured
    assert "what the test measured" in page.locator(".replay__legend").inner_text()
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "replay-attempt.png"), full_page=True)
    response = page.goto(f"{live_server.url}/recordings/of/test_attempt/{attempt_id + 1000}")
    assert response is not None and response.status == 404
