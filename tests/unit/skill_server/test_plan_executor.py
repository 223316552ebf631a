"""A plan run by the sequencer on a synchronously stepped lab world: lines in order, blocks taking the right path,
settings lasting to the end, the watchdog, the time cap, and the one-motor-goal rule."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import replace

import pytest
from skill_sim_helpers import TOKEN

from skill_server.errors import ResourceBusy
from skill_server.goals import EventKind, GoalSnapshot, GoalStatus
from skill_server.plans import executor
from skill_server.plans.model import (
    DriveLine,
    IfLine,
    InvalidPlan,
    Plan,
    PlanCondition,
    PlanLine,
    RepeatLine,
    SayLine,
    SetLine,
    SkillLine,
    WaitLine,
)
from skill_server.plans.validation import check_plan
from skill_server.sequencer import Sequencer, attach_sequencer
from skill_server.sim.battery import BatterySpec
from skill_server.sim.robot_model import TELEBOT
from skill_server.sim.world import World


@pytest.fixture
def lab() -> Iterator[tuple[World, Sequencer]]:
    """The default lab, stepped by the test, with a sequencer attached and the test in control."""
    with World("lab", realtime=False, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        yield world, sequencer


def start(sequencer: Sequencer, *steps: PlanLine, preempt: bool = False) -> str:
    checked = check_plan(Plan("unit", tuple(steps)), sequencer.registry, sequencer.spec)
    return sequencer.run_plan(TOKEN, checked, preempt).goal.goal_id


def run(world: World, sequencer: Sequencer, goal_id: str, limit_s: float = 120.0) -> GoalSnapshot:
    goal = sequencer.goals.get(goal_id)
    assert goal is not None
    start_s = world.snapshot.sim_time_s
    while not goal.status.is_terminal and world.snapshot.sim_time_s - start_s < limit_s:
        world.step_for(0.1)
    return goal.snapshot()


def messages(sequencer: Sequencer, goal_id: str, kind: EventKind) -> list[str]:
    goal = sequencer.goals.get(goal_id)
    assert goal is not None
    return [event.message for event in goal.events if event.kind is kind]


def test_repeat_and_if_take_the_right_path_in_order(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal_id = start(
        sequencer,
        RepeatLine(1, 1, 3, (SayLine(2, 3, "round"),)),
        IfLine(3, 1, PlanCondition("obstacle_within", 0.3), (SayLine(4, 3, "near"),), (SayLine(6, 3, "far"),)),
        IfLine(7, 1, PlanCondition("obstacle_within", 0.3, negate=True), (SayLine(8, 3, "clear"),)),
        IfLine(9, 1, PlanCondition("goal_reached"), (SayLine(10, 3, "reached"),), (SayLine(12, 3, "not yet"),)),
    )
    final = run(world, sequencer, goal_id)
    assert final.status is GoalStatus.SUCCEEDED, final.message
    assert final.skill == "plan:unit" and final.motor
    assert messages(sequencer, goal_id, EventKind.STEP_STARTED) == [
        "line 1: repeat 3", "line 2: round", "line 2: round", "line 2: round",
        "line 3: if obstacle_within 0.3: no, else", "line 6: far",
        "line 7: if not obstacle_within 0.3: yes, then", "line 8: clear",
        "line 9: if goal_reached: no, else", "line 12: not yet",
    ]


def test_goal_reached_follows_the_last_skill_line(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal_id = start(
        sequencer,
        SkillLine(1, 1, "go_to_goal", (("goal_x_m", 0.6), ("goal_y_m", 0.0))),
        IfLine(2, 1, PlanCondition("goal_reached"), (SayLine(3, 3, "there"),), (SayLine(5, 3, "lost"),)),
        WaitLine(7, 1, PlanCondition("goal_reached"), 1.0),
    )
    final = run(world, sequencer, goal_id)
    assert final.status is GoalStatus.SUCCEEDED, final.message
    assert "line 3: there" in messages(sequencer, goal_id, EventKind.STEP_STARTED)
    assert math.hypot(world.snapshot.ground_truth.x_m - 0.6, world.snapshot.ground_truth.y_m) < 0.12


def test_set_max_speed_clamps_the_wheels_until_the_plan_ends(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal_id = start(sequencer, SetLine(1, 1, "max_speed", 0.1), DriveLine(2, 1, 0.4, 0.0, 2.0))
    fastest = 0.0
    goal = sequencer.goals.get(goal_id)
    assert goal is not None
    while not goal.status.is_terminal:
        fastest = max(fastest, world.step_for(0.05).odometry.linear_mps)
    assert goal.status is GoalStatus.SUCCEEDED
    assert 0.08 < fastest <= 0.105
    assert world.snapshot.ground_truth.x_m < 0.25


def test_a_drive_into_a_wall_stops_short_and_aborts_naming_its_line(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal_id = start(sequencer, SayLine(1, 1, "off we go"), DriveLine(2, 1, 0.5, 0.0, 30.0))
    final = run(world, sequencer, goal_id)
    assert (final.status, final.error_code) == (GoalStatus.ABORTED, "COLLISION_AHEAD")
    assert final.message.startswith("line 2: stopped: an obstacle")
    world.step_for(1.0)
    wall_face_m, radius_m = 4.0, sequencer.spec.body_radius_m
    assert world.snapshot.ground_truth.x_m + radius_m < wall_face_m - 0.03
    assert abs(world.snapshot.odometry.linear_mps) < 0.01


def test_set_watchdog_sets_the_bases_drive_watchdog_until_the_plan_ends(lab: tuple[World, Sequencer]) -> None:
    """`set watchdog` means what SetLimits' watchdog means (the time a direct drive lasts without a newer one), not
    a time limit on the plan's steps: a drive four times longer succeeds, and the value in force comes back after."""
    world, sequencer = lab
    world.set_limits(TOKEN, 0.0, 0.0, 2.0)
    goal_id = start(sequencer, SetLine(1, 1, "watchdog", 0.5), DriveLine(2, 1, 0.2, 0.0, 2.0))
    goal = sequencer.goals.get(goal_id)
    assert goal is not None
    seen = set()
    while not goal.status.is_terminal:
        world.step_for(0.1)
        seen.add(world.limits.watchdog_s)
    assert goal.status is GoalStatus.SUCCEEDED, goal.snapshot().message
    assert 0.5 in seen, seen
    assert world.limits.watchdog_s == 2.0, "the watchdog in force before the plan comes back when it ends"


def test_a_cancelled_plan_gives_the_watchdog_back_and_a_new_controller_keeps_its_own(
        lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    world.set_limits(TOKEN, 0.0, 0.0, 1.5)
    goal_id = start(sequencer, SetLine(1, 1, "watchdog", 0.3), SetLine(2, 1, "watchdog", 4.0),
                    WaitLine(3, 1, None, 30.0))
    world.step_for(0.5)
    assert world.limits.watchdog_s == 4.0
    assert sequencer.cancel(TOKEN, goal_id).status is GoalStatus.CANCELED
    assert world.limits.watchdog_s == 1.5, "two `set watchdog` lines: the value before the first comes back"
    # The turn passes while a plan holds the watchdog: the new controller starts from the robot's own settings.
    start(sequencer, SetLine(1, 1, "watchdog", 0.3), WaitLine(2, 1, None, 30.0))
    world.step_for(0.3)
    assert world.limits.watchdog_s == 0.3
    world.set_controller("someone-else")
    world.step_for(0.3)
    assert world.limits.watchdog_s == 1000.0  # the fixture's robot setting, not the first controller's 1.5


def test_a_watchdog_outside_what_setlimits_accepts_is_refused_naming_its_line(lab: tuple[World, Sequencer]) -> None:
    _world, sequencer = lab
    for value in (0.1, 5.5):
        with pytest.raises(InvalidPlan) as refused:
            start(sequencer, SetLine(3, 2, "watchdog", value))
        assert "watchdog" in str(refused.value) or "value" in str(refused.value), refused.value


def test_a_wait_whose_condition_never_holds_times_out(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal_id = start(sequencer, WaitLine(4, 2, PlanCondition("obstacle_within", 0.1), 0.5))
    final = run(world, sequencer, goal_id)
    assert (final.status, final.error_code) == (GoalStatus.ABORTED, "TIMEOUT")
    assert final.message.startswith("line 4: obstacle_within 0.1 did not hold within 0.5 s")


def test_the_plan_is_capped_in_sim_time(lab: tuple[World, Sequencer], monkeypatch: pytest.MonkeyPatch) -> None:
    world, sequencer = lab
    monkeypatch.setattr(executor, "MAX_PLAN_S", 1.0)  # the real cap (1 800 s) works the same, only longer
    goal_id = start(sequencer, SayLine(1, 1, "patience"), WaitLine(2, 1, PlanCondition("goal_reached"), 0.0))
    final = run(world, sequencer, goal_id)
    assert (final.status, final.error_code) == (GoalStatus.ABORTED, "TIMEOUT")
    assert final.message.startswith("line 2: the plan ran past its limit of 1 s")


def test_a_plan_holds_the_wheels_like_any_motor_goal(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    first = start(sequencer, WaitLine(1, 1, None, 30.0))
    world.step_for(0.2)
    with pytest.raises(ResourceBusy):
        start(sequencer, SayLine(1, 1, "me too"))
    with pytest.raises(ResourceBusy):
        sequencer.activate(TOKEN, "go_to_goal", {"goal_x_m": 1.0}, preempt=False)
    second = start(sequencer, SayLine(1, 1, "me first"), preempt=True)
    preempted = sequencer.goals.get(first)
    assert preempted is not None
    assert (preempted.status, preempted.error_code) == (GoalStatus.CANCELED, "PREEMPTED")
    assert run(world, sequencer, second).status is GoalStatus.SUCCEEDED


def test_cancelling_mid_line_stops_the_base_and_the_feedback_names_the_line(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal_id = start(sequencer, SayLine(1, 1, "go"), DriveLine(2, 1, 0.3, 0.0, 5.0))
    world.step_for(1.0)
    assert world.snapshot.odometry.linear_mps > 0.2
    final = sequencer.cancel(TOKEN, goal_id)
    assert final.status is GoalStatus.CANCELED
    assert dict(final.feedback.values)["line"] == 2.0 and final.feedback.state.startswith("line 2: drive")
    world.step_for(1.0)
    assert abs(world.snapshot.odometry.linear_mps) < 0.01


def test_lines_done_in_no_time_do_not_cost_a_tick_each(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal_id = start(sequencer, RepeatLine(1, 1, 20, (SetLine(2, 3, "max_speed", 0.2), SayLine(3, 3, "x"))))
    world.step_for(2 * world.tick_dt_s)
    goal = sequencer.goals.get(goal_id)
    assert goal is not None and goal.status is GoalStatus.SUCCEEDED


def test_battery_below_reads_the_charge_the_skills_see() -> None:
    spec = replace(TELEBOT, battery=BatterySpec(initial_charge=0.4))
    with World("lab", realtime=False, deadman_timeout_s=1000.0, spec=spec) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        goal_id = start(sequencer,
                        IfLine(1, 1, PlanCondition("battery_below", 0.3), (SayLine(2, 3, "low"),),
                               (SayLine(4, 3, "enough"),)),
                        WaitLine(6, 1, PlanCondition("battery_below", 0.5), 1.0))
        final = run(world, sequencer, goal_id)
    assert final.status is GoalStatus.SUCCEEDED, final.message
    assert messages(sequencer, goal_id, EventKind.STEP_STARTED) == [
        "line 1: if battery_below 0.3: no, else", "line 4: enough", "line 6: wait until battery_below 0.5 at most 1 s"]


def test_the_planned_path_of_a_go_to_reaches_the_watchers_through_a_plan_and_a_round_trip(
        lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    plan_id = start(sequencer, SkillLine(1, 1, "go_to_goal", (("goal_x_m", 1.5), ("goal_y_m", 0.5))))
    world.step_for(0.5)
    in_plan = sequencer.goals.get(plan_id)
    assert in_plan is not None and in_plan.feedback.planned_path[-1] == (1.5, 0.5)
    trip = sequencer.activate(TOKEN, "round_trip", {"goal_x_m": 1.0, "goal_y_m": -0.5}, preempt=True).goal
    world.step_for(0.5)
    in_trip = sequencer.goals.get(trip.goal_id)
    assert in_trip is not None and in_trip.feedback.planned_path[-1] == (1.0, -0.5)


def test_line_seen_reads_the_line_sensor_over_the_tape(lab: tuple[World, Sequencer]) -> None:
    from skill_server.sim.geometry import Pose2D
    from skill_server.sim.scenes import LAB_LINE

    world, sequencer = lab
    goal_id = start(sequencer, WaitLine(1, 1, PlanCondition("line_seen"), 0.5))  # at the dock, off the tape
    final = run(world, sequencer, goal_id)
    assert final.message.startswith("line 1: line_seen did not hold within 0.5 s"), final.message
    world.set_pose(Pose2D(-0.5 - LAB_LINE.sensor.ahead_m, LAB_LINE.y_min_m, 0.0))  # the sensor over the bottom run
    goal_id = start(sequencer, IfLine(1, 1, PlanCondition("line_seen"), (SayLine(2, 3, "on the tape"),)),
                    IfLine(3, 1, PlanCondition("line_seen", negate=True), (SayLine(4, 3, "lost"),)))
    final = run(world, sequencer, goal_id)
    assert final.status is GoalStatus.SUCCEEDED, final.message
    assert messages(sequencer, goal_id, EventKind.STEP_STARTED) == [
        "line 1: if line_seen: yes, then", "line 2: on the tape", "line 3: if not line_seen: no, else"]
