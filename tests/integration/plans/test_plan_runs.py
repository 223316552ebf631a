"""Running stored plans through the middleware on real skill servers: on a lab robot only during one's turn, on
one's practice robot at any time; line progress, the end state (ABORTED at the failing line), cancel; and a plan's
predicted end point on the practice robot agrees with the lab robot's in the same scene (within 5 cm)."""

from __future__ import annotations

import json
import math
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from middleware.robots.processes import SkillServerProcess
from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, _let_go, make_test_app
from tests.integration.lab.test_skills_api import take_control
from tests.integration.plans.conftest import PlansLab, api, run_on_practice

SHORT = 'say "start"\ndrive 0.2 0 for 1s\n'
SQUARE_CORNER = "drive 0.25 0 for 2s\nturn_to 90deg\ndrive 0.25 0 for 1.5s\n"


def wait_for_end(client: LabClient, answer: dict, timeout_s: float = 60) -> dict:
    """Polls the run's goal until it ends; its final state."""
    deadline = time.monotonic() + timeout_s
    path = f"/api/robots/{answer['robot']}/goals/{answer['goal']['goal_id']}"
    while time.monotonic() < deadline:
        status, body = api(client, "GET", path)
        assert status == 200, body
        if body["goal"]["status"] in ("succeeded", "aborted", "canceled"):
            return body["goal"]
        time.sleep(0.2)
    raise AssertionError(f"the plan did not end within {timeout_s} s")


def latest_pose(client: LabClient, robot: str) -> dict[str, float]:
    """The robot's newest odometry pose, read from its telemetry channel."""
    telemetry = client.websocket(f"/ws/robots/{robot}/telemetry")
    latest = None
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        message = telemetry.receive(timeout=1)
        if message is None:
            continue
        data = json.loads(message)
        if data.get("type") == "telemetry":
            latest = data["odometry"]["pose"]
            if time.monotonic() > deadline - 4:  # a second of messages: the newest is where it stands
                break
    telemetry.close()
    assert latest is not None, "no telemetry within 5 s"
    return latest


def _create(client: LabClient, name: str, text: str) -> int:
    status, body = api(client, "POST", "/api/plans", {"name": name, "text": text})
    assert status == 201, body
    return body["plan"]["id"]


def test_a_plan_runs_on_a_lab_robot_only_during_the_turn(plans_lab: PlansLab) -> None:
    ann, bob = plans_lab.client("student1"), plans_lab.client("student2")
    plan_id = _create(ann, "short", SHORT)
    status, body = api(ann, "POST", f"/api/plans/{plan_id}/runs", {"target": "lab-1"})
    assert status == 403 and body["error"]["code"] == "not_controller"
    queue = take_control(ann)
    assert api(ann, "POST", "/api/robots/lab-1/dock", {})[0] == 200  # the shared robot, wherever tests left it
    status, answer = api(ann, "POST", f"/api/plans/{plan_id}/runs", {"target": "lab-1"})
    assert status == 202, answer
    assert answer["goal"]["skill"] == "plan:short" and answer["goal_channel"].startswith("/ws/robots/lab-1/goals/")
    goal = wait_for_end(ann, answer)
    assert goal["status"] == "succeeded", goal
    # Someone else, waiting in the queue, is refused as an observer.
    bob.websocket("/ws/robots/lab-1/queue")
    status, body = api(bob, "POST", f"/api/plans/{plan_id}/runs", {"target": "lab-1"})
    assert status == 404  # ann's plan is private
    queue.close()


def test_the_practice_robot_reports_the_line_running_and_the_failing_line(plans_lab: PlansLab) -> None:
    ann = plans_lab.client("student1")
    plan_id = _create(ann, "fails-on-3", 'say "go"\ndrive 0.2 0 for 1s\nwait_until obstacle_within 0.05 timeout 1s\n')
    # Not running yet: the run claims the robot and answers at once, starting; it starts once that is committed.
    status, claimed = api(ann, "POST", f"/api/plans/{plan_id}/runs", {"target": "practice", "beside": "lab-1"})
    assert status == 202 and claimed["starting"] and claimed["goal"] is None, claimed
    assert claimed["robot"] == "practice-student1" and "goal_channel" not in claimed
    status, answer = run_on_practice(ann, plan_id, {"beside": "lab-1", "from_dock": True})
    assert status == 202, answer
    assert answer["practice"] and answer["robot"] == "practice-student1" and not answer["starting"]
    lines_seen = set()
    goal_channel = ann.websocket(answer["goal_channel"])
    deadline = time.monotonic() + 60
    final = None
    while final is None and time.monotonic() < deadline:
        message = goal_channel.receive(timeout=5)
        if message is None:
            continue
        data = json.loads(message)
        feedback = data.get("feedback") if data["type"] == "goal_feedback" else (data.get("goal") or {}).get("feedback")
        if feedback and feedback.get("values", {}).get("line"):
            lines_seen.add(int(feedback["values"]["line"]))
        if data["type"] == "goal" and data["goal"]["status"] in ("succeeded", "aborted", "canceled"):
            final = data["goal"]
    assert final is not None and final["status"] == "aborted", final
    assert final["message"].startswith("line 3"), final
    assert 2 in lines_seen, lines_seen
    # A long plan is canceled and stops.
    long_id = _create(ann, "long", "drive 0.1 0 for 60s\n")
    status, answer = run_on_practice(ann, long_id, {})
    assert status == 202, answer
    time.sleep(1.0)
    status, body = api(ann, "DELETE", answer["cancel_url"])
    assert status == 200, body
    assert wait_for_end(ann, answer)["status"] == "canceled"


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_a_plan_refused_for_its_watchdog_line_starts_no_practice_robot(plans_lab: PlansLab) -> None:
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.teaching.practice_robots import practice_manager

    ann = plans_lab.client("student1")
    plan_id = _create(ann, "watchdog-first", 'say "hi"\nrepeat 2 {\n  set watchdog 0.5s\n}\n')
    status, answer = run_on_practice(ann, plan_id, {"from_dock": True})
    assert status == 403 and answer["error"]["message"].startswith("Line 3: "), answer
    app = plans_lab.server.app
    with session_factory(app)() as session:
        ann_id = session.query(User.id).filter_by(username="student1").scalar()
    assert practice_manager(app).get(ann_id) is None
    assert not practice_manager(app).farm.robots()


@pytest.fixture
def fresh_lab_and_robot(tmp_path: Path) -> Iterator[tuple[LiveServer, SkillServerProcess]]:
    """A lab whose lab-1 is a skill server of its own, fresh at its dock in the lab scene (the session's robot
    has been moved by other tests), on SQLite; and lab-1's process."""
    from middleware.robots.processes import wait_until_serving
    from middleware.teaching.practice_robots import practice_manager

    robot = SkillServerProcess("lab-1", "lab", echo=False)
    robot.start()
    app = None
    server = None
    try:
        wait_until_serving(robot.address)
        app = make_test_app(f"sqlite:///{tmp_path / 'fresh.sqlite3'}", f"lab-1={robot.address}", tmp_path)
        server = LiveServer(app)
        yield server, robot
    finally:
        if server is not None:
            server.stop()
        if app is not None:
            practice_manager(app).shutdown()
            _let_go(app)  # its ticker, links, farm and practice keeper
        robot.stop()


@pytest.fixture
def fresh_lab(fresh_lab_and_robot: tuple[LiveServer, SkillServerProcess]) -> LiveServer:
    """The lab of fresh_lab_and_robot."""
    return fresh_lab_and_robot[0]


def test_the_predicted_end_point_agrees_with_the_lab_robot_within_5_cm(fresh_lab: LiveServer) -> None:
    """The prediction ("Try on my practice robot": a copy of lab-1 in fast mode) against lab-1 in real time."""
    from tests.integration.plans.test_plan_predictions import predict

    ann = LabClient(fresh_lab.url)
    assert ann.login("student1", STUDENT_PASSWORD) == 302
    plan_id = _create(ann, "corner", SQUARE_CORNER)
    predicted = predict(ann, plan_id, {"beside": "lab-1", "from_dock": False})[-1]
    assert predicted["type"] == "end" and predicted["goal"]["status"] == "succeeded", predicted
    assert predicted["start"]["at"] == "lab_robot", predicted["start"]
    assert predicted["wall_s"] < predicted["sim_time_s"], "the prediction ran in fast mode"
    predicted_end = predicted["trace"][-1]
    queue = take_control(ann)
    start = latest_pose(ann, "lab-1")
    status, real = api(ann, "POST", f"/api/plans/{plan_id}/runs", {"target": "lab-1"})
    assert status == 202, real
    assert wait_for_end(ann, real)["status"] == "succeeded"
    real_end = latest_pose(ann, "lab-1")
    queue.close()
    moved_m = math.hypot(real_end["x_m"] - start["x_m"], real_end["y_m"] - start["y_m"])
    assert moved_m > 0.5, "the plan must move the robot for the comparison to mean anything"
    error_m = math.hypot(predicted_end["x_m"] - real_end["x_m"], predicted_end["y_m"] - real_end["y_m"])
    print(f"predicted end {predicted_end} ({predicted['sim_time_s']:.1f} s of plan in {predicted['wall_s']:.2f} s), "
          f"lab end {real_end}, apart {error_m * 100:.1f} cm")
    assert error_m <= 0.05, f"the end points are {error_m * 100:.1f} cm apart"


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_a_plan_on_a_lab_robot_ends_when_its_user_goes_away(plans_lab: PlansLab) -> None:
    """The deadman decision (README, Plans): closing the page ends the turn one grace later, and the robot ends the
    plan CONTROL_REVOKED."""
    grace_s = 3.0
    plans_lab.server.app.config["ACCESS_GRACE_S"] = grace_s
    ann = plans_lab.client("student1")
    plan_id = _create(ann, "slow-and-long", "drive 0.02 0 for 120s\n")
    queue = take_control(ann)
    assert api(ann, "POST", "/api/robots/lab-1/dock", {})[0] == 200  # the shared robot, wherever tests left it
    status, answer = api(ann, "POST", f"/api/plans/{plan_id}/runs", {"target": "lab-1"})
    assert status == 202, answer
    time.sleep(0.5)
    status, body = api(ann, "GET", f"/api/robots/lab-1/goals/{answer['goal']['goal_id']}")
    assert body["goal"]["status"] == "executing", body
    queue.close()
    left_at = time.monotonic()
    goal = wait_for_end(ann, answer, timeout_s=grace_s + 30)
    ended_after_s = time.monotonic() - left_at
    print(f"the plan ended {ended_after_s:.1f} s after its user left (grace {grace_s} s)")
    assert goal["status"] == "aborted" and goal["error_code"] == "CONTROL_REVOKED", goal
    assert ended_after_s <= grace_s + 5.0, "the plan outlived its user's presence by more than the grace"


def test_the_practice_robot_starts_where_the_lab_robot_stands_now(fresh_lab: LiveServer) -> None:
    ann = LabClient(fresh_lab.url)
    assert ann.login("student1", STUDENT_PASSWORD) == 302
    queue = take_control(ann)
    status, moved = api(ann, "POST", f"/api/plans/{_create(ann, 'corner', SQUARE_CORNER)}/runs", {"target": "lab-1"})
    assert status == 202, moved
    assert wait_for_end(ann, moved)["status"] == "succeeded"
    lab = latest_pose(ann, "lab-1")
    still_id = _create(ann, "still", "wait 3s\n")
    status, tried = run_on_practice(ann, still_id, {"beside": "lab-1", "from_dock": False})
    assert status == 202, tried
    assert tried["start"]["at"] == "lab_robot", tried["start"]
    practice = latest_pose(ann, tried["robot"])
    apart_m = math.hypot(practice["x_m"] - lab["x_m"], practice["y_m"] - lab["y_m"])
    turned_rad = abs(math.remainder(practice["theta_rad"] - lab["theta_rad"], math.tau))
    print(f"lab-1 at {lab}, the practice robot starts at {practice}: {apart_m * 100:.1f} cm, {turned_rad:.3f} rad")
    assert apart_m <= 0.02 and turned_rad <= 0.02
    # "Start at the dock", the alternative, still carries it back there, away from where lab-1 stands.
    status, docked = run_on_practice(ann, still_id, {"beside": "lab-1", "from_dock": True})
    assert status == 202 and docked["start"]["at"] == "dock", docked
    at_dock = latest_pose(ann, docked["robot"])
    assert math.hypot(at_dock["x_m"] - lab["x_m"], at_dock["y_m"] - lab["y_m"]) > 0.5
    queue.close()



def test_a_lab_robot_that_does_not_answer_leaves_the_practice_robot_at_its_dock(
        fresh_lab_and_robot: tuple[LiveServer, SkillServerProcess]) -> None:
    server, lab_robot = fresh_lab_and_robot
    ann = LabClient(server.url)
    assert ann.login("student1", STUDENT_PASSWORD) == 302
    plan_id = _create(ann, "still", "wait 1s\n")
    lab_robot.stop()
    status, tried = run_on_practice(ann, plan_id, {"beside": "lab-1", "from_dock": False})
    assert status == 202, tried
    assert tried["start"] == {"at": "dock", "message": "Starts at its dock: lab-1 did not answer."}
