"""Goal RPCs over real gRPC: activation, refusals with status codes, two watchers, cancel, schema, map."""

from __future__ import annotations

import math
import threading
import time

import grpc
import pytest

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.server import SkillServer

DEADLINE_S = 30.0
TOKEN = "goal-token"


def value(raw: object) -> robot_pb2.ParameterValue:
    """A ParameterValue of raw's type."""
    if isinstance(raw, bool):
        return robot_pb2.ParameterValue(bool_value=raw)
    if isinstance(raw, int):
        return robot_pb2.ParameterValue(int_value=raw)
    if isinstance(raw, str):
        return robot_pb2.ParameterValue(string_value=raw)
    return robot_pb2.ParameterValue(double_value=raw)


def activate(robot: robot_pb2_grpc.RobotStub, skill: str, preempt: bool = False, token: str = TOKEN,
             **parameters: object) -> robot_pb2.ActivateSkillResponse:
    """ActivateSkill with plain keyword parameters."""
    request = robot_pb2.ActivateSkillRequest(token=token, skill=skill, preempt=preempt,
                                             parameters={k: value(v) for k, v in parameters.items()})
    return robot.ActivateSkill(request, timeout=DEADLINE_S)


@pytest.fixture
def controlled(fresh_server: SkillServer) -> robot_pb2_grpc.RobotStub:
    """A stub on a fresh server whose controller is TOKEN."""
    channel = grpc.insecure_channel(fresh_server.address)
    robot = robot_pb2_grpc.RobotStub(channel)
    robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
    yield robot
    channel.close()


def test_two_watchers_see_the_same_events_and_the_final_state(controlled: robot_pb2_grpc.RobotStub) -> None:
    goal = activate(controlled, "go_to_goal", goal_x_m=1.0, goal_y_m=0.0).goal
    assert goal.status == robot_pb2.GOAL_STATUS_ACCEPTED and goal.goal_id
    seen: dict[int, list[robot_pb2.GoalUpdate]] = {0: [], 1: []}

    def watch(index: int) -> None:
        stream = controlled.WatchGoal(robot_pb2.WatchGoalRequest(goal_id=goal.goal_id), timeout=DEADLINE_S)
        seen[index].extend(stream)

    threads = [threading.Thread(target=watch, args=(i,)) for i in (0, 1)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for updates in seen.values():
        events = [u.event.kind for u in updates if u.WhichOneof("update") == "event"]
        assert events[0] == robot_pb2.GOAL_EVENT_KIND_STARTED
        assert robot_pb2.GOAL_EVENT_KIND_GOAL_REACHED in events
        assert any(u.WhichOneof("update") == "feedback" for u in updates)
        final = updates[-1].state
        assert final.status == robot_pb2.GOAL_STATUS_SUCCEEDED and final.goal_reached
    assert [u.event for u in seen[0] if u.WhichOneof("update") == "event"] == [
        u.event for u in seen[1] if u.WhichOneof("update") == "event"
    ]
    kept = controlled.GetGoal(robot_pb2.GetGoalRequest(goal_id=goal.goal_id), timeout=DEADLINE_S)
    assert kept.status == robot_pb2.GOAL_STATUS_SUCCEEDED


def test_a_watcher_that_begins_while_the_goal_is_accepted_sees_it_execute_then_cancel(
    fresh_server: SkillServer, controlled: robot_pb2_grpc.RobotStub
) -> None:
    """A perceptive goal changes status only on its first tick and when canceled: both must reach the watcher."""
    world, sequencer = fresh_server.world, fresh_server.sequencer
    assert sequencer is not None
    loop_held, release = threading.Event(), threading.Event()
    activated: list[str] = []

    def activate_then_hold_the_loop() -> None:
        activation = sequencer.activate(TOKEN, "detect_obstacle", {}, False)
        activated.append(activation.goal.goal_id)
        loop_held.set()
        release.wait(DEADLINE_S)  # no tick, so the goal stays accepted while the watch begins

    holder = threading.Thread(target=world.run_in_loop, args=(activate_then_hold_the_loop,))
    holder.start()
    try:
        assert loop_held.wait(DEADLINE_S)
        stream = controlled.WatchGoal(robot_pb2.WatchGoalRequest(goal_id=activated[0]), timeout=DEADLINE_S)
        first = next(stream)
        assert first.state.status == robot_pb2.GOAL_STATUS_ACCEPTED
    finally:
        release.set()
        holder.join()
    states = (update.state.status for update in stream if update.WhichOneof("update") == "state")
    assert next(states) == robot_pb2.GOAL_STATUS_EXECUTING
    controlled.CancelGoal(robot_pb2.CancelGoalRequest(token=TOKEN, goal_id=activated[0]), timeout=DEADLINE_S)
    assert list(states)[-1] == robot_pb2.GOAL_STATUS_CANCELED


def test_cancel_reports_the_error_left_and_preemption_is_per_request(controlled: robot_pb2_grpc.RobotStub) -> None:
    first = activate(controlled, "go_to_goal", goal_x_m=-3.0, goal_y_m=0.0).goal
    with pytest.raises(grpc.RpcError) as busy:
        activate(controlled, "orientation_control", heading_rad=1.0)
    assert busy.value.code() == grpc.StatusCode.FAILED_PRECONDITION and first.goal_id in busy.value.details()
    second = activate(controlled, "go_to_goal", preempt=True, goal_x_m=-3.0, goal_y_m=0.5)
    assert second.preempted_goal_id == first.goal_id
    old = controlled.GetGoal(robot_pb2.GetGoalRequest(goal_id=first.goal_id), timeout=DEADLINE_S)
    assert (old.status, old.error_code) == (robot_pb2.GOAL_STATUS_CANCELED, "PREEMPTED")
    canceled = controlled.CancelGoal(robot_pb2.CancelGoalRequest(token=TOKEN, goal_id=second.goal.goal_id),
                                     timeout=DEADLINE_S)
    assert canceled.status == robot_pb2.GOAL_STATUS_CANCELED and "error left" in canceled.message
    assert canceled.feedback.distance_error_m > 0


@pytest.mark.parametrize(
    ("parameters", "field"),
    [
        ({"goal_x_m": math.nan}, "goal_x_m"),
        ({"goal_y_m": math.inf}, "goal_y_m"),
        ({"speed_mps": -0.3}, "speed_mps"),
        ({"speed_mps": "slow"}, "speed_mps"),
        ({"max_error_m": True}, "max_error_m"),
        ({"wings": 2.0}, "wings"),
    ],
)
def test_invalid_parameters_are_invalid_argument_naming_the_field(
    controlled: robot_pb2_grpc.RobotStub, parameters: dict[str, object], field: str
) -> None:
    with pytest.raises(grpc.RpcError) as refused:
        activate(controlled, "go_to_goal", **parameters)
    assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT and field in refused.value.details()
    assert controlled.ListGoals(robot_pb2.ListGoalsRequest(), timeout=DEADLINE_S).goals == []


def test_refusals_for_unknown_skill_and_missing_control(controlled: robot_pb2_grpc.RobotStub) -> None:
    with pytest.raises(grpc.RpcError) as unknown:
        activate(controlled, "teleport")
    assert unknown.value.code() == grpc.StatusCode.NOT_FOUND
    with pytest.raises(grpc.RpcError) as stale:
        activate(controlled, "go_to_goal", token="not-the-controller")
    assert stale.value.code() == grpc.StatusCode.PERMISSION_DENIED
    with pytest.raises(grpc.RpcError) as no_map:
        controlled.GetMap(robot_pb2.GetMapRequest(), timeout=DEADLINE_S)
    assert no_map.value.code() == grpc.StatusCode.FAILED_PRECONDITION
    with pytest.raises(grpc.RpcError) as needs_map:
        activate(controlled, "localization")
    assert needs_map.value.code() == grpc.StatusCode.FAILED_PRECONDITION


def test_the_published_schema_is_what_the_server_enforces(controlled: robot_pb2_grpc.RobotStub) -> None:
    skills = controlled.ListSkills(robot_pb2.ListSkillsRequest(), timeout=DEADLINE_S).skills
    names = {s.name for s in skills}
    assert {"go_to_goal", "orientation_control", "wall_following", "round_trip", "detect_obstacle",
            "environment_modelling", "localization", "direct_control"} <= names
    for skill in skills:
        for parameter in skill.parameters:
            if parameter.type != robot_pb2.PARAMETER_TYPE_DOUBLE:
                continue
            above = parameter.maximum + max(1.0, abs(parameter.maximum))
            with pytest.raises(grpc.RpcError) as refused:
                activate(controlled, skill.name, **{parameter.name: above})
            assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT
            assert parameter.name in refused.value.details()


def test_mapping_then_get_map_returns_an_occupancy_grid(controlled: robot_pb2_grpc.RobotStub) -> None:
    mapping = activate(controlled, "environment_modelling", duration_s=1.0).goal
    updates = list(controlled.WatchGoal(robot_pb2.WatchGoalRequest(goal_id=mapping.goal_id), timeout=DEADLINE_S))
    assert updates[-1].state.status == robot_pb2.GOAL_STATUS_SUCCEEDED
    grid = controlled.GetMap(robot_pb2.GetMapRequest(), timeout=DEADLINE_S)
    assert len(grid.cells) == grid.width_cells * grid.height_cells and grid.scans_integrated >= 1
    assert any(0 < cell <= 100 for cell in grid.cells) and 255 in grid.cells
    activate(controlled, "localization", initial_spread_m=0.05)
    stream = controlled.StreamLocalization(robot_pb2.StreamLocalizationRequest(rate_hz=10, max_particles=50),
                                           timeout=DEADLINE_S)
    update = next(u for u in stream if u.active)
    stream.cancel()
    assert 0 < len(update.particles) <= 50 and update.std_x_m > 0


def test_clearing_the_map_ends_mapping_and_localization_and_only_the_controller_may(
        controlled: robot_pb2_grpc.RobotStub) -> None:
    mapping = activate(controlled, "environment_modelling", use_floor_plan=True).goal
    time.sleep(0.5)
    localization = activate(controlled, "localization", initial_spread_m=0.05).goal
    with pytest.raises(grpc.RpcError) as refused:
        controlled.ClearMap(robot_pb2.ClearMapRequest(token="someone-else"), timeout=DEADLINE_S)
    assert refused.value.code() == grpc.StatusCode.PERMISSION_DENIED
    assert controlled.GetMap(robot_pb2.GetMapRequest(), timeout=DEADLINE_S).width_cells > 0
    cleared = controlled.ClearMap(robot_pb2.ClearMapRequest(token=TOKEN), timeout=DEADLINE_S)
    assert set(cleared.ended_goal_ids) == {mapping.goal_id, localization.goal_id}
    for goal in (mapping, localization):
        state = controlled.GetGoal(robot_pb2.GetGoalRequest(goal_id=goal.goal_id), timeout=DEADLINE_S)
        assert state.status == robot_pb2.GOAL_STATUS_CANCELED
    with pytest.raises(grpc.RpcError) as no_map:
        controlled.GetMap(robot_pb2.GetMapRequest(), timeout=DEADLINE_S)
    assert no_map.value.code() == grpc.StatusCode.FAILED_PRECONDITION


def newest_telemetry(robot: robot_pb2_grpc.RobotStub) -> robot_pb2.Telemetry:
    """One telemetry message from a fresh stream."""
    stream = robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=20), timeout=DEADLINE_S)
    message = next(iter(stream))
    stream.cancel()
    return message


def test_the_return_to_the_dock_ends_every_goal_and_restarts_odometry_at_the_spawn(
        controlled: robot_pb2_grpc.RobotStub) -> None:
    activate(controlled, "direct_control", linear_mps=0.2, angular_radps=0.2, duration_s=10.0)
    time.sleep(1.0)
    driven = newest_telemetry(controlled)
    assert math.hypot(driven.ground_truth.x_m, driven.ground_truth.y_m) > 0.1
    mapping = activate(controlled, "environment_modelling", use_floor_plan=True).goal
    going = activate(controlled, "go_to_goal", preempt=True, goal_x_m=-1.5, goal_y_m=1.0).goal
    with pytest.raises(grpc.RpcError) as refused:
        controlled.ReturnToDock(robot_pb2.ReturnToDockRequest(token=""), timeout=DEADLINE_S)
    assert refused.value.code() == grpc.StatusCode.PERMISSION_DENIED, "an empty token while someone controls"
    docked = controlled.ReturnToDock(robot_pb2.ReturnToDockRequest(token=TOKEN), timeout=DEADLINE_S)
    assert set(docked.ended_goal_ids) == {mapping.goal_id, going.goal_id}
    after = newest_telemetry(controlled)
    for pose in (after.ground_truth, after.odometry.pose):
        assert math.hypot(pose.x_m - docked.dock.x_m, pose.y_m - docked.dock.y_m) < 0.02
    state = controlled.GetGoal(robot_pb2.GetGoalRequest(goal_id=mapping.goal_id), timeout=DEADLINE_S)
    assert state.status == robot_pb2.GOAL_STATUS_ABORTED


def test_supervisory_actions_take_an_empty_token_only_while_nobody_has_control(
        controlled: robot_pb2_grpc.RobotStub) -> None:
    controlled.SetController(robot_pb2.SetControllerRequest(token=""), timeout=DEADLINE_S)
    assert controlled.ReturnToDock(robot_pb2.ReturnToDockRequest(token=""), timeout=DEADLINE_S).dock.x_m == 0.0
    controlled.ClearMap(robot_pb2.ClearMapRequest(token=""), timeout=DEADLINE_S)
    with pytest.raises(grpc.RpcError) as refused:
        controlled.ClearMap(robot_pb2.ClearMapRequest(token="a-guess"), timeout=DEADLINE_S)
    assert refused.value.code() == grpc.StatusCode.PERMISSION_DENIED


def place(robot: robot_pb2_grpc.RobotStub, x_m: float, y_m: float, theta_rad: float = 0.0,
          token: str = TOKEN) -> robot_pb2.PlaceRobotResponse:
    """PlaceRobot at (x_m, y_m, theta_rad)."""
    pose = robot_pb2.Pose2D(x_m=x_m, y_m=y_m, theta_rad=theta_rad)
    return robot.PlaceRobot(robot_pb2.PlaceRobotRequest(token=token, pose=pose), timeout=DEADLINE_S)


def test_placing_the_robot_ends_every_goal_and_restarts_odometry_at_the_pose(
        controlled: robot_pb2_grpc.RobotStub) -> None:
    going = activate(controlled, "go_to_goal", goal_x_m=-1.5, goal_y_m=1.0).goal
    with pytest.raises(grpc.RpcError) as refused:
        place(controlled, 0.5, -0.4, token="")
    assert refused.value.code() == grpc.StatusCode.PERMISSION_DENIED, "an empty token while someone controls"
    placed = place(controlled, 0.5, -0.4, 1.2)
    assert list(placed.ended_goal_ids) == [going.goal_id]
    after = newest_telemetry(controlled)
    for pose in (after.ground_truth, after.odometry.pose):
        assert math.hypot(pose.x_m - 0.5, pose.y_m + 0.4) < 0.02
        assert abs(pose.theta_rad - 1.2) < 0.02
    state = controlled.GetGoal(robot_pb2.GetGoalRequest(goal_id=going.goal_id), timeout=DEADLINE_S)
    assert state.status in (robot_pb2.GOAL_STATUS_ABORTED, robot_pb2.GOAL_STATUS_CANCELED)


def test_a_placement_off_the_floor_or_into_a_wall_is_refused_naming_the_field(
        controlled: robot_pb2_grpc.RobotStub) -> None:
    info = controlled.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=DEADLINE_S)
    obstacle = min(info.scene_boxes, key=lambda box: math.hypot(box.center_x_m, box.center_y_m))  # on the floor
    for (x_m, y_m, theta_rad), field in (((math.nan, 0.0, 0.0), "pose.x_m"), ((0.0, 0.0, math.inf), "pose.theta_rad"),
                                         ((0.0, 1e6, 0.0), "pose.y_m"),
                                         ((obstacle.center_x_m, obstacle.center_y_m, 0.0), "pose")):
        with pytest.raises(grpc.RpcError) as refused:
            place(controlled, x_m, y_m, theta_rad)
        assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert dict(refused.value.trailing_metadata() or ())["field"] == field, refused.value.details()
    after = newest_telemetry(controlled)
    assert math.hypot(after.ground_truth.x_m, after.ground_truth.y_m) < 0.02, "nothing moved on refusal"
