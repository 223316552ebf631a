"""Goals of the motor skills run by the sequencer on a synchronously stepped lab world."""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest
from skill_sim_helpers import TOKEN

from skill_server.errors import InvalidParameter, NotController, ResourceBusy, UnknownSkill
from skill_server.goals import EventKind, GoalSnapshot, GoalStatus
from skill_server.robot import Robot
from skill_server.sequencer import Sequencer, attach_sequencer
from skill_server.sim.world import World


@pytest.fixture
def lab() -> Iterator[tuple[World, Sequencer]]:
    """The default lab, stepped by the test, with a sequencer attached and the test in control."""
    with World("lab", realtime=False, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        yield world, sequencer


def run_until_done(world: World, sequencer: Sequencer, goal_id: str, limit_s: float = 60.0) -> GoalSnapshot:
    """Steps the world until the goal ends (or the limit passes) and returns its final state."""
    goal = sequencer.goals.get(goal_id)
    assert goal is not None
    start_s = world.snapshot.sim_time_s
    while not goal.status.is_terminal and world.snapshot.sim_time_s - start_s < limit_s:
        world.step_for(0.25)
    return goal.snapshot()


def test_go_to_goal_drives_around_the_crate_and_reports_reaching_it(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal = sequencer.activate(TOKEN, "go_to_goal", {"goal_x_m": 3.2, "goal_y_m": 1.4}, preempt=False).goal
    assert goal.status is GoalStatus.ACCEPTED
    closest_m = math.inf
    final = None
    while final is None or not final.status.is_terminal:
        closest_m = min(closest_m, min(world.step_for(0.25).sonar_ranges_m))
        final = sequencer.goals.get(goal.goal_id).snapshot()
    truth = world.snapshot.ground_truth
    assert final.status is GoalStatus.SUCCEEDED and final.goal_reached
    assert math.hypot(truth.x_m - 3.2, truth.y_m - 1.4) < 0.1
    assert closest_m > 0.05  # never touched the crate
    kinds = [e.kind for e in sequencer.goals.get(goal.goal_id).events]
    assert kinds[0] is EventKind.STARTED and EventKind.GOAL_REACHED in kinds


def test_a_goal_inside_an_obstacle_is_aborted_as_unreachable(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal = sequencer.activate(TOKEN, "go_to_goal", {"goal_x_m": 2.5, "goal_y_m": 1.4}, preempt=False).goal
    final = run_until_done(world, sequencer, goal.goal_id)
    assert (final.status, final.error_code) == (GoalStatus.ABORTED, "UNREACHABLE")
    assert "inside an obstacle" in final.message and "error left" in final.message


def test_a_goal_outside_the_walls_is_aborted_as_unreachable(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal = sequencer.activate(TOKEN, "go_to_goal", {"goal_x_m": 6.0, "goal_y_m": 0.0}, preempt=False).goal
    final = run_until_done(world, sequencer, goal.goal_id)
    assert (final.status, final.error_code) == (GoalStatus.ABORTED, "UNREACHABLE")


def test_cancel_mid_way_stops_the_robot_and_reports_the_error_left(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal = sequencer.activate(TOKEN, "go_to_goal", {"goal_x_m": -3.0, "goal_y_m": 0.0}, preempt=False).goal
    world.step_for(3.0)
    final = sequencer.cancel(TOKEN, goal.goal_id)
    assert (final.status, final.error_code) == (GoalStatus.CANCELED, "CANCELED")
    assert final.feedback.distance_error_m > 0.5 and "error left" in final.message
    stopped = world.step_for(1.0)
    assert abs(stopped.commanded_linear_mps) < 1e-9 and abs(stopped.commanded_angular_radps) < 1e-9


def test_a_second_motor_goal_is_refused_or_preempts_as_asked(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    first = sequencer.activate(TOKEN, "go_to_goal", {"goal_x_m": -3.0}, preempt=False).goal
    world.step_for(0.5)
    with pytest.raises(ResourceBusy) as busy:
        sequencer.activate(TOKEN, "orientation_control", {"heading_rad": 1.0}, preempt=False)
    assert busy.value.holder_goal_id == first.goal_id
    second = sequencer.activate(TOKEN, "orientation_control", {"heading_rad": 1.0}, preempt=True)
    assert second.preempted_goal_id == first.goal_id
    old = sequencer.goals.get(first.goal_id).snapshot()
    assert (old.status, old.error_code) == (GoalStatus.CANCELED, "PREEMPTED")
    assert run_until_done(world, sequencer, second.goal.goal_id).status is GoalStatus.SUCCEEDED


def test_perceptive_skills_run_beside_a_motor_skill(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    watcher = sequencer.activate(TOKEN, "detect_obstacle", {"warning_distance_m": 1.0}, preempt=False).goal
    mover = sequencer.activate(TOKEN, "go_to_goal", {"goal_x_m": 3.0, "goal_y_m": -0.6}, preempt=False).goal
    assert run_until_done(world, sequencer, mover.goal_id).status is GoalStatus.SUCCEEDED
    live = sequencer.goals.get(watcher.goal_id)
    assert live.status is GoalStatus.EXECUTING
    assert any(e.kind is EventKind.OBSTACLE_DETECTED for e in live.events)


def test_a_direct_drive_command_preempts_the_motor_goal(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal = sequencer.activate(TOKEN, "go_to_goal", {"goal_x_m": -3.0}, preempt=False).goal
    world.step_for(1.0)
    Robot(world, sequencer).drive(TOKEN, 1, 0.0, 0.0)
    world.step_for(0.1)
    final = sequencer.goals.get(goal.goal_id).snapshot()
    assert (final.status, final.error_code) == (GoalStatus.CANCELED, "PREEMPTED")


def test_the_drive_that_preempts_a_motor_goal_moves_the_base(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    sequencer.activate(TOKEN, "orientation_control", {"heading_rad": 3.0}, preempt=False)
    world.step_for(0.2)
    Robot(world, sequencer).drive(TOKEN, 1, 0.3, 0.0)
    moving = world.step_for(0.3)  # within the deadman's window: no second command is needed
    assert moving.commanded_linear_mps > 0.1 and abs(moving.commanded_angular_radps) < 1e-6


def test_revoking_control_aborts_the_motor_goal(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal = sequencer.activate(TOKEN, "orientation_control", {"heading_rad": 3.0}, preempt=False).goal
    world.step_for(0.2)
    world.set_controller("")
    world.step_for(0.1)
    final = sequencer.goals.get(goal.goal_id).snapshot()
    assert (final.status, final.error_code) == (GoalStatus.ABORTED, "CONTROL_REVOKED")


@pytest.mark.parametrize("heading_rad", [math.pi / 2, -2.5, 0.3])
def test_orientation_control_turns_within_tolerance(lab: tuple[World, Sequencer], heading_rad: float) -> None:
    world, sequencer = lab
    goal = sequencer.activate(TOKEN, "orientation_control", {"heading_rad": heading_rad, "tolerance_rad": 0.02},
                              preempt=False).goal
    final = run_until_done(world, sequencer, goal.goal_id)
    assert final.status is GoalStatus.SUCCEEDED
    error = math.remainder(world.snapshot.ground_truth.theta_rad - heading_rad, 2 * math.pi)
    assert abs(error) < 0.04


def test_round_trip_comes_back_to_the_start_pose(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal = sequencer.activate(TOKEN, "round_trip", {"goal_x_m": 1.5, "goal_y_m": 1.0}, preempt=False).goal
    final = run_until_done(world, sequencer, goal.goal_id, limit_s=90.0)
    truth = world.snapshot.ground_truth
    assert final.status is GoalStatus.SUCCEEDED
    # The navigation stack tracks its pose against the floor plan: back by the true pose, not only by odometry's.
    assert math.hypot(truth.x_m, truth.y_m) < 0.05 and abs(truth.theta_rad) < 0.05, truth
    steps = [e.message for e in sequencer.goals.get(goal.goal_id).events if e.kind is EventKind.STEP_STARTED]
    assert len(steps) == 3


def test_direct_control_goal_holds_velocities_for_its_duration(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    goal = sequencer.activate(TOKEN, "direct_control", {"linear_mps": 0.2, "duration_s": 1.0}, False).goal
    final = run_until_done(world, sequencer, goal.goal_id)
    world.step_for(0.5)
    assert final.status is GoalStatus.SUCCEEDED
    assert world.snapshot.ground_truth.x_m == pytest.approx(0.2, abs=0.05)


@pytest.mark.parametrize(
    ("skill", "parameters", "field"),
    [
        ("go_to_goal", {"goal_x_m": math.nan}, "goal_x_m"),
        ("go_to_goal", {"goal_y_m": math.inf}, "goal_y_m"),
        ("go_to_goal", {"speed_mps": -0.2}, "speed_mps"),
        ("go_to_goal", {"speed_mps": "fast"}, "speed_mps"),
        ("go_to_goal", {"max_error_m": True}, "max_error_m"),
        ("go_to_goal", {"colour": 1.0}, "colour"),
        ("orientation_control", {"tolerance_rad": 0.0}, "tolerance_rad"),
        ("round_trip", {"speed_mps": 9.0}, "speed_mps"),
        ("direct_control", {"linear_mps": -math.inf}, "linear_mps"),
    ],
)
def test_invalid_parameters_are_refused_naming_the_field(
    lab: tuple[World, Sequencer], skill: str, parameters: dict[str, object], field: str
) -> None:
    _, sequencer = lab
    with pytest.raises(InvalidParameter) as refused:
        sequencer.activate(TOKEN, skill, parameters, preempt=False)
    assert refused.value.field == field and field in refused.value.message
    assert sequencer.goals.all() == []


def test_unknown_skill_and_stale_token_are_refused(lab: tuple[World, Sequencer]) -> None:
    _, sequencer = lab
    with pytest.raises(UnknownSkill):
        sequencer.activate(TOKEN, "fly", {}, preempt=False)
    with pytest.raises(NotController):
        sequencer.activate("someone-else", "go_to_goal", {}, preempt=False)
