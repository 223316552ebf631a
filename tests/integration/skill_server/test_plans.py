"""RunPlan on a real skill server in fast mode: a plan runs as one motor goal, names its lines, stops the wheels
when cancelled, aborts on the line that failed, shares the wheels with nothing, and is refused whole when any
part of it is wrong."""

from __future__ import annotations

import math
import time

import grpc
import pytest

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.server import SkillServer

DEADLINE_S = 30.0
TOKEN = "plan-token"
Step = robot_pb2.PlanStep


def value(raw: object) -> robot_pb2.ParameterValue:
    if isinstance(raw, str):
        return robot_pb2.ParameterValue(string_value=raw)
    return robot_pb2.ParameterValue(double_value=float(raw))  # type: ignore[arg-type]


def skill(line: int, name: str, duration_s: float = 0.0, **parameters: object) -> Step:
    return Step(line=line, column=1, skill=robot_pb2.SkillStep(
        skill=name, duration_s=duration_s, parameters={k: value(v) for k, v in parameters.items()}))


def drive(line: int, linear_mps: float, angular_radps: float, duration_s: float) -> Step:
    return Step(line=line, column=1, drive=robot_pb2.DriveStep(linear_mps=linear_mps, angular_radps=angular_radps,
                                                               duration_s=duration_s))


def say(line: int, text: str, column: int = 1) -> Step:
    return Step(line=line, column=column, say=robot_pb2.SayStep(text=text))


def wait(line: int, duration_s: float) -> Step:
    return Step(line=line, column=1, wait=robot_pb2.WaitStep(duration_s=duration_s))


def repeat(line: int, count: int, *body: Step, column: int = 1) -> Step:
    return Step(line=line, column=column, repeat=robot_pb2.RepeatStep(count=count,
                                                                      body=robot_pb2.PlanBlock(steps=body)))


def branch(line: int, kind: str, threshold: float, then: list[Step], otherwise: list[Step]) -> Step:
    return Step(line=line, column=1, branch=robot_pb2.IfStep(
        condition=robot_pb2.PlanCondition(kind=kind, value=threshold), then_block=robot_pb2.PlanBlock(steps=then),
        else_block=robot_pb2.PlanBlock(steps=otherwise)))


def run_plan(robot: robot_pb2_grpc.RobotStub, name: str, *steps: Step, preempt: bool = False,
             token: str = TOKEN) -> robot_pb2.ActivateSkillResponse:
    request = robot_pb2.RunPlanRequest(token=token, name=name, plan=robot_pb2.PlanBlock(steps=steps), preempt=preempt)
    return robot.RunPlan(request, timeout=DEADLINE_S)


def watch_to_end(robot: robot_pb2_grpc.RobotStub, goal_id: str, timeout_s: float = 300.0
                 ) -> tuple[robot_pb2.GoalState, list[robot_pb2.GoalEvent], list[robot_pb2.GoalFeedback]]:
    events, feedback, final = [], [], None
    for update in robot.WatchGoal(robot_pb2.WatchGoalRequest(goal_id=goal_id), timeout=timeout_s):
        kind = update.WhichOneof("update")
        if kind == "event":
            events.append(update.event)
        elif kind == "feedback":
            feedback.append(update.feedback)
        else:
            final = update.state
    assert final is not None
    return final, events, feedback


def speed_now(robot: robot_pb2_grpc.RobotStub) -> float:
    stream = robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=20.0), timeout=DEADLINE_S)
    telemetry = next(iter(stream))
    stream.cancel()
    return math.hypot(telemetry.odometry.linear_mps, telemetry.odometry.angular_radps)


@pytest.fixture
def controlled(fresh_server: SkillServer) -> robot_pb2_grpc.RobotStub:
    """A stub on a fresh fast-mode server whose controller is TOKEN."""
    channel = grpc.insecure_channel(fresh_server.address)
    robot = robot_pb2_grpc.RobotStub(channel)
    robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
    yield robot
    channel.close()


def test_a_plan_goes_to_two_points_and_follows_a_wall(fresh_server: SkillServer,
                                                      controlled: robot_pb2_grpc.RobotStub) -> None:
    started = run_plan(controlled, "tour",
                       say(1, "to the lane's end"),
                       skill(2, "go_to_goal", goal_x_m=1.5, goal_y_m=0.0),
                       skill(3, "go_to_goal", goal_x_m=1.5, goal_y_m=2.3),
                       skill(4, "orientation_control", heading_rad=math.pi),
                       skill(5, "wall_following", 6.0, side="right", distance_m=0.5))
    assert started.goal.skill == "plan:tour" and started.goal.motor
    listed = controlled.ListGoals(robot_pb2.ListGoalsRequest(), timeout=DEADLINE_S).goals
    assert [goal.goal_id for goal in listed] == [started.goal.goal_id]
    final, events, feedback = watch_to_end(controlled, started.goal.goal_id)
    assert final.status == robot_pb2.GOAL_STATUS_SUCCEEDED, final.message
    steps = [e.message for e in events if e.kind == robot_pb2.GOAL_EVENT_KIND_STEP_STARTED]
    assert steps == ["line 1: to the lane's end", "line 2: go_to_goal", "line 3: go_to_goal",
                     "line 4: orientation_control", "line 5: wall_following for 6 s"]
    lines = {int(f.values["line"]) for f in feedback}
    assert {2, 3, 5} <= lines and all(f.state.startswith(f"line {int(f.values['line'])}: ") for f in feedback)
    truth = fresh_server.world.snapshot.ground_truth
    assert truth.x_m < 1.2, "wall following went west along the north wall"
    assert 2.2 < truth.y_m < 2.8, f"about 0.5 m from the north wall (at 3.0 m), {truth}"
    kept = controlled.GetGoal(robot_pb2.GetGoalRequest(goal_id=started.goal.goal_id), timeout=DEADLINE_S)
    assert kept.status == robot_pb2.GOAL_STATUS_SUCCEEDED


def test_a_plan_cancelled_mid_line_stops_the_robot_and_reports_the_line(
        controlled: robot_pb2_grpc.RobotStub) -> None:
    started = run_plan(controlled, "cancel-me", say(1, "go"), drive(2, 0.3, 0.0, 8.0), say(3, "never said"))
    goal_id = started.goal.goal_id
    deadline = time.monotonic() + DEADLINE_S
    while time.monotonic() < deadline:
        state = controlled.GetGoal(robot_pb2.GetGoalRequest(goal_id=goal_id), timeout=DEADLINE_S)
        if state.feedback.values.get("line") == 2 and speed_now(controlled) > 0.2:
            break
    else:
        pytest.fail("the plan never got to line 2 at speed")
    canceled = controlled.CancelGoal(robot_pb2.CancelGoalRequest(token=TOKEN, goal_id=goal_id), timeout=DEADLINE_S)
    assert canceled.status == robot_pb2.GOAL_STATUS_CANCELED
    assert canceled.message.startswith("line 2: canceled by the controller")
    assert canceled.feedback.values["line"] == 2 and canceled.feedback.state.startswith("line 2: drive")
    time.sleep(0.5)  # fast mode: seconds of sim time
    assert speed_now(controlled) < 0.01
    _, events, _ = watch_to_end(controlled, goal_id)
    assert "line 3: never said" not in [e.message for e in events]


def test_a_plan_whose_step_collides_aborts_with_that_steps_line(fresh_server: SkillServer,
                                                                 controlled: robot_pb2_grpc.RobotStub) -> None:
    started = run_plan(controlled, "into-the-wall", say(1, "east"), drive(2, 0.5, 0.0, 30.0), say(3, "unreached"))
    final, events, _ = watch_to_end(controlled, started.goal.goal_id)
    assert (final.status, final.error_code) == (robot_pb2.GOAL_STATUS_ABORTED, "COLLISION_AHEAD")
    assert final.message.startswith("line 2: ")
    assert any(e.kind == robot_pb2.GOAL_EVENT_KIND_FAILED and e.message.startswith("line 2: ") for e in events)
    time.sleep(0.3)
    truth = fresh_server.world.snapshot.ground_truth
    assert truth.x_m + fresh_server.world.spec.body_radius_m < 4.0 - 0.03, "stopped short of the east wall"
    assert speed_now(controlled) < 0.01


def test_two_plans_cannot_drive_the_wheels_at_once(controlled: robot_pb2_grpc.RobotStub) -> None:
    first = run_plan(controlled, "first", wait(1, 60.0)).goal
    for refused_call in (lambda: run_plan(controlled, "second", say(1, "me too")),
                         lambda: controlled.ActivateSkill(robot_pb2.ActivateSkillRequest(
                             token=TOKEN, skill="go_to_goal"), timeout=DEADLINE_S)):
        with pytest.raises(grpc.RpcError) as busy:
            refused_call()
        assert busy.value.code() == grpc.StatusCode.FAILED_PRECONDITION and first.goal_id in busy.value.details()
    second = run_plan(controlled, "second", wait(1, 60.0), preempt=True)
    assert second.preempted_goal_id == first.goal_id
    old = controlled.GetGoal(robot_pb2.GetGoalRequest(goal_id=first.goal_id), timeout=DEADLINE_S)
    assert (old.status, old.error_code) == (robot_pb2.GOAL_STATUS_CANCELED, "PREEMPTED")
    controlled.Drive(robot_pb2.DriveCommand(token=TOKEN, sequence=1, linear_mps=0.0, angular_radps=0.2),
                     timeout=DEADLINE_S)
    taken = controlled.GetGoal(robot_pb2.GetGoalRequest(goal_id=second.goal.goal_id), timeout=DEADLINE_S)
    assert (taken.status, taken.error_code) == (robot_pb2.GOAL_STATUS_CANCELED, "PREEMPTED")
    with pytest.raises(grpc.RpcError) as stale:
        run_plan(controlled, "stale", say(1, "hi"), token="not-the-controller")
    assert stale.value.code() == grpc.StatusCode.PERMISSION_DENIED


def test_repeat_and_if_branches_take_the_right_path(controlled: robot_pb2_grpc.RobotStub) -> None:
    started = run_plan(controlled, "paths",
                       repeat(1, 2, say(2, "round", column=3), drive(3, 0.0, 0.5, 0.2)),
                       branch(4, "obstacle_within", 0.3, [say(5, "too close")], [say(7, "room to move")]),
                       branch(9, "obstacle_within", 5.0, [say(10, "a wall in sight")], []))
    final, events, _ = watch_to_end(controlled, started.goal.goal_id)
    assert final.status == robot_pb2.GOAL_STATUS_SUCCEEDED, final.message
    assert [e.message for e in events if e.kind == robot_pb2.GOAL_EVENT_KIND_STEP_STARTED] == [
        "line 1: repeat 2", "line 2: round", "line 3: drive 0 m/s 0.5 rad/s for 0.2 s", "line 2: round",
        "line 3: drive 0 m/s 0.5 rad/s for 0.2 s", "line 4: if obstacle_within 0.3: no, else",
        "line 7: room to move", "line 9: if obstacle_within 5: yes, then", "line 10: a wall in sight"]


def deep(levels: int) -> Step:
    step = say(levels + 1, "deep")
    for level in range(levels, 0, -1):
        step = repeat(level, 1, step, column=level)
    return step


@pytest.mark.parametrize(("steps", "where"), [
    ([say(1, "ok"), deep(9)], "line 9, column 9: depth: "),
    ([repeat(3, 1000, say(4, "again"))], "line 3, column 1: count: "),
    ([drive(2, math.nan, 0.0, 1.0)], "line 2, column 1: linear_mps: "),
    ([wait(5, math.inf)], "line 5, column 1: duration_s: "),
    ([skill(4, "teleport")], "line 4, column 1: skill: unknown skill 'teleport'"),
    ([skill(6, "go_to_goal", goal_x_m=99.0)], "line 6, column 1: goal_x_m: "),
    ([skill(6, "go_to_goal", wings=2.0)], "line 6, column 1: wings: "),
    ([skill(6, "wall_following", side="up")], "line 6, column 1: side: "),
    ([Step(line=8, column=2)], "line 8, column 2: kind: "),
    ([say(1, "x" * 201)], "line 1, column 1: text: "),
])
def test_hostile_plans_are_refused_naming_line_and_field_with_nothing_moving(
        shared_server: SkillServer, robot: robot_pb2_grpc.RobotStub, steps: list[Step], where: str) -> None:
    robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
    with pytest.raises(grpc.RpcError) as refused:
        run_plan(robot, "hostile", drive(1, 0.3, 0.0, 5.0), *steps)
    assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert where in refused.value.details(), refused.value.details()
    assert robot.ListGoals(robot_pb2.ListGoalsRequest(), timeout=DEADLINE_S).goals == []
    time.sleep(0.2)
    assert speed_now(robot) < 0.01 and abs(shared_server.world.snapshot.ground_truth.x_m) < 0.01


def test_a_bad_plan_name_and_an_empty_plan_are_refused(robot: robot_pb2_grpc.RobotStub) -> None:
    controlled = robot
    robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
    with pytest.raises(grpc.RpcError) as bad_name:
        run_plan(controlled, "no spaces please", say(1, "hi"))
    assert bad_name.value.code() == grpc.StatusCode.INVALID_ARGUMENT and "name: " in bad_name.value.details()
    with pytest.raises(grpc.RpcError) as empty:
        run_plan(controlled, "empty")
    assert empty.value.code() == grpc.StatusCode.INVALID_ARGUMENT and "steps: " in empty.value.details()


def test_a_plan_ends_when_control_changes_hands(controlled: robot_pb2_grpc.RobotStub) -> None:
    """The deadman rule for plans: a plan lives under its controller's token and ends when the turn does."""
    goal_id = run_plan(controlled, "my-turn", drive(1, 0.0, 0.3, 30.0)).goal.goal_id
    controlled.SetController(robot_pb2.SetControllerRequest(token="next-student"), timeout=DEADLINE_S)
    final, _, _ = watch_to_end(controlled, goal_id, timeout_s=DEADLINE_S)
    assert (final.status, final.error_code) == (robot_pb2.GOAL_STATUS_ABORTED, "CONTROL_REVOKED")
    assert final.message.startswith("line 1: the controller changed")
    time.sleep(0.3)
    assert speed_now(controlled) < 0.01
