"""Low-level commands over real gRPC in fast mode: velocity ceilings and the watchdog (SetLimits/GetLimits), and the
simulated battery (drain with motion, BATTERY_EMPTY, recharge at the dock)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator

import grpc
import pytest

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.server import SkillServer, create_server
from skill_server.sim.battery import BatterySpec
from skill_server.sim.geometry import Pose2D
from skill_server.sim.snapshots import RobotSnapshot

DEADLINE_S = 10.0
TOKEN = "limits-token"


@pytest.fixture
def controlled(fresh_server: SkillServer) -> Iterator[robot_pb2_grpc.RobotStub]:
    """A stub on a fresh server whose controller is TOKEN."""
    with grpc.insecure_channel(fresh_server.address) as channel:
        robot = robot_pb2_grpc.RobotStub(channel)
        robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
        yield robot


def set_limits(robot: robot_pb2_grpc.RobotStub, token: str = TOKEN, **values: float) -> robot_pb2.Limits:
    return robot.SetLimits(robot_pb2.SetLimitsRequest(token=token, **values), timeout=DEADLINE_S)


def drive(robot: robot_pb2_grpc.RobotStub, sequence: int, linear_mps: float,
          angular_radps: float = 0.0) -> robot_pb2.DriveAck:
    return robot.Drive(robot_pb2.DriveCommand(token=TOKEN, sequence=sequence, linear_mps=linear_mps,
                                              angular_radps=angular_radps), timeout=DEADLINE_S)


def snapshots_until(server: SkillServer, done: Callable[[RobotSnapshot], bool],
                    timeout_s: float = 20.0) -> list[RobotSnapshot]:
    """Every snapshot the loop publishes (read as they come) up to the first for which done() holds."""
    seen: list[RobotSnapshot] = []
    deadline = time.monotonic() + timeout_s
    last_tick = -1
    while time.monotonic() < deadline:
        snapshot = server.world.wait_for_snapshot(last_tick, 1.0)
        if snapshot is None:
            continue
        last_tick = snapshot.tick
        seen.append(snapshot)
        if done(snapshot):
            return seen
    raise AssertionError(f"not within {timeout_s} s; last snapshot {seen[-1] if seen else None}")


def test_get_limits_reports_the_robot_s_own_and_the_ranges(controlled: robot_pb2_grpc.RobotStub) -> None:
    limits = controlled.GetLimits(robot_pb2.GetLimitsRequest(), timeout=DEADLINE_S)
    assert (limits.max_linear_mps, limits.max_angular_radps, limits.watchdog_s) == (0.5, 1.5, 2.0)
    assert (limits.robot_max_linear_mps, limits.robot_max_angular_radps) == (0.5, 1.5)
    assert (limits.min_watchdog_s, limits.max_watchdog_s) == (0.2, 5.0)


def test_a_lower_ceiling_clamps_a_drive_and_a_skill(fresh_server: SkillServer,
                                                    controlled: robot_pb2_grpc.RobotStub) -> None:
    limits = set_limits(controlled, max_linear_mps=0.2, max_angular_radps=0.5)
    assert (limits.max_linear_mps, limits.max_angular_radps, limits.watchdog_s) == (0.2, 0.5, 2.0), "0 kept it"
    ack = drive(controlled, 1, 0.5, -1.5)
    assert (ack.linear_mps, ack.angular_radps) == (0.2, -0.5), "the ack says what the base was given"
    seen = snapshots_until(fresh_server, lambda s: s.sim_time_s > 1.5 and s.last_applied_sequence == 1)
    assert max(s.commanded_linear_mps for s in seen) == pytest.approx(0.2)
    assert min(s.commanded_angular_radps for s in seen) == pytest.approx(-0.5)
    assert seen[-1].odometry.linear_mps == pytest.approx(0.2, abs=0.03)

    drive(controlled, 2, 0.0)
    value = {"linear_mps": robot_pb2.ParameterValue(double_value=0.5),
             "duration_s": robot_pb2.ParameterValue(double_value=2.0)}
    controlled.ActivateSkill(robot_pb2.ActivateSkillRequest(token=TOKEN, skill="direct_control", parameters=value),
                             timeout=DEADLINE_S)
    start_s = fresh_server.world.snapshot.sim_time_s
    seen = snapshots_until(fresh_server, lambda s: s.sim_time_s > start_s + 1.5)
    assert max(s.commanded_linear_mps for s in seen) == pytest.approx(0.2), "a skill obeys the ceiling too"


def distance_driven_until_the_deadman_stops(server: SkillServer, robot: robot_pb2_grpc.RobotStub,
                                            sequence: int) -> float:
    """Drives at 0.3 m/s with one command and waits for the deadman: how far the robot went (by the true pose,
    which no polling gap blurs: the ramps up and down cancel, so it is 0.3 m/s times the timeout)."""
    start = server.world.snapshot.ground_truth
    drive(robot, sequence, 0.3)
    snapshots_until(server, lambda s: s.last_applied_sequence == sequence and s.deadman_stopped
                    and s.commanded_linear_mps == 0.0)
    end = server.world.snapshot.ground_truth
    return math.hypot(end.x_m - start.x_m, end.y_m - start.y_m)


def test_the_watchdog_stops_the_base_after_the_timeout_set(fresh_server: SkillServer,
                                                           controlled: robot_pb2_grpc.RobotStub) -> None:
    assert set_limits(controlled, watchdog_s=0.5).watchdog_s == 0.5
    info = controlled.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=DEADLINE_S)
    assert info.deadman_timeout_s == 0.5
    assert distance_driven_until_the_deadman_stops(fresh_server, controlled, 1) == pytest.approx(0.15, abs=0.03)
    assert set_limits(controlled, watchdog_s=1.5).watchdog_s == 1.5
    assert distance_driven_until_the_deadman_stops(fresh_server, controlled, 2) == pytest.approx(0.45, abs=0.03)


@pytest.mark.parametrize(
    ("values", "field"),
    [
        ({"max_linear_mps": 0.9}, "max_linear_mps"),
        ({"max_linear_mps": -0.1}, "max_linear_mps"),
        ({"max_linear_mps": math.nan}, "max_linear_mps"),
        ({"max_angular_radps": math.inf}, "max_angular_radps"),
        ({"max_angular_radps": 1.6}, "max_angular_radps"),
        ({"watchdog_s": 0.1}, "watchdog_s"),
        ({"watchdog_s": 5.5}, "watchdog_s"),
        ({"max_linear_mps": 0.3, "watchdog_s": -math.inf}, "watchdog_s"),
    ],
)
def test_invalid_values_are_refused_naming_the_field_and_change_nothing(
        controlled: robot_pb2_grpc.RobotStub, values: dict[str, float], field: str) -> None:
    before = controlled.GetLimits(robot_pb2.GetLimitsRequest(), timeout=DEADLINE_S)
    with pytest.raises(grpc.RpcError) as refused:
        set_limits(controlled, **values)
    assert refused.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert dict(refused.value.trailing_metadata())["field"] == field
    assert refused.value.details().startswith(field)
    assert controlled.GetLimits(robot_pb2.GetLimitsRequest(), timeout=DEADLINE_S) == before


def test_only_the_controller_sets_limits_and_they_reset_when_control_changes(
        controlled: robot_pb2_grpc.RobotStub) -> None:
    for token, code in (("", grpc.StatusCode.UNAUTHENTICATED), ("someone-else", grpc.StatusCode.PERMISSION_DENIED)):
        with pytest.raises(grpc.RpcError) as refused:
            set_limits(controlled, token=token, max_linear_mps=0.1)
        assert refused.value.code() == code
    assert set_limits(controlled, max_linear_mps=0.1, watchdog_s=3.0).max_linear_mps == 0.1
    controlled.SetController(robot_pb2.SetControllerRequest(token="next-student"), timeout=DEADLINE_S)
    limits = controlled.GetLimits(robot_pb2.GetLimitsRequest(), timeout=DEADLINE_S)
    assert (limits.max_linear_mps, limits.watchdog_s) == (0.5, 2.0), "a new turn starts from the robot's own"


# A battery that lasts 3 s of driving at top speed and recharges from empty in 2 s.
TINY_BATTERY = BatterySpec(full_drive_s=3.0, recharge_s=2.0)


@pytest.fixture
def tiny_battery_server() -> Iterator[SkillServer]:
    running = create_server(port=0, realtime=False, deadman_timeout_s=2.0, robot_name="battery-bot",
                            battery=TINY_BATTERY)
    yield running
    running.stop(grace_s=0.5)


def newest_battery(robot: robot_pb2_grpc.RobotStub) -> robot_pb2.Battery:
    stream = robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=20), timeout=DEADLINE_S)
    message = next(iter(stream))
    stream.cancel()
    return message.battery


def test_the_battery_drains_with_motion_empties_aborts_the_goal_and_recharges_at_the_dock(
        tiny_battery_server: SkillServer) -> None:
    server = tiny_battery_server
    with grpc.insecure_channel(server.address) as channel:
        robot = robot_pb2_grpc.RobotStub(channel)
        robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
        at_dock = newest_battery(robot)
        assert at_dock.charge == pytest.approx(1.0) and at_dock.charging and not at_dock.empty
        server.world.set_pose(Pose2D(0.0, 0.5, 0.0))  # off the dock: standing still drains almost nothing
        time.sleep(0.3)
        idle = newest_battery(robot)
        assert not idle.charging and idle.charge > 0.999

        parameters = {"linear_mps": robot_pb2.ParameterValue(double_value=0.5),
                      "angular_radps": robot_pb2.ParameterValue(double_value=1.5),
                      "duration_s": robot_pb2.ParameterValue(double_value=10.0)}
        goal = robot.ActivateSkill(robot_pb2.ActivateSkillRequest(token=TOKEN, skill="direct_control",
                                                                  parameters=parameters), timeout=DEADLINE_S).goal
        charges = [s.battery.charge for s in snapshots_until(server, lambda s: s.battery.empty)]
        assert charges == sorted(charges, reverse=True), "driving only drains"
        assert charges[0] > 0.9 and any(0.1 < charge < 0.9 for charge in charges) and charges[-1] == 0.0
        deadline = time.monotonic() + DEADLINE_S
        state = robot.GetGoal(robot_pb2.GetGoalRequest(goal_id=goal.goal_id), timeout=DEADLINE_S)
        while state.status != robot_pb2.GOAL_STATUS_ABORTED and time.monotonic() < deadline:
            time.sleep(0.05)
            state = robot.GetGoal(robot_pb2.GetGoalRequest(goal_id=goal.goal_id), timeout=DEADLINE_S)
        assert (state.status, state.error_code) == (robot_pb2.GOAL_STATUS_ABORTED, "BATTERY_EMPTY")
        assert "battery is empty" in state.message

        empty = newest_battery(robot)
        assert empty.empty and empty.charge == 0.0
        with pytest.raises(grpc.RpcError) as refused:
            drive(robot, 1, 0.2)
        assert refused.value.code() == grpc.StatusCode.FAILED_PRECONDITION
        assert "battery is empty" in refused.value.details() and "dock" in refused.value.details()
        assert drive(robot, 2, 0.0).linear_mps == 0.0, "a stop is always accepted"
        snapshots_until(server, lambda s: s.commanded_linear_mps == 0.0)  # the base has braked to a stop
        again = robot.ActivateSkill(robot_pb2.ActivateSkillRequest(token=TOKEN, skill="direct_control",
                                                                   parameters=parameters), timeout=DEADLINE_S).goal
        start_s = server.world.snapshot.sim_time_s
        seen = snapshots_until(server, lambda s: s.sim_time_s > start_s + 0.5
                               and server.robot.goal(again.goal_id).status.is_terminal)
        assert server.robot.goal(again.goal_id).error_code == "BATTERY_EMPTY"
        assert max(abs(s.commanded_linear_mps) for s in seen) == 0.0, "an empty base does not move"

        robot.ReturnToDock(robot_pb2.ReturnToDockRequest(token=TOKEN), timeout=DEADLINE_S)
        recharged = snapshots_until(server, lambda s: not s.battery.empty)
        assert recharged[-1].battery.charging and recharged[-1].battery.charge >= 0.05
        assert all(s.battery.empty for s in recharged[:-1]), "empty until recharged to 5 %"
        assert drive(robot, 3, 0.2).linear_mps == 0.2, "a recharged robot moves again"
