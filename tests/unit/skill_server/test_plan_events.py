"""A plan's `on <event> { }` on a synchronously stepped lab world: the line running is cut short when its event
happens, the body runs in its place and the plan goes on; the checks refuse an on that cannot work, naming its line."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace

import pytest
from skill_sim_helpers import TOKEN

from skill_server.goals import EventKind, GoalFeedback, GoalSnapshot, GoalStatus
from skill_server.plans.model import (
    DriveLine,
    InvalidPlan,
    OnLine,
    Plan,
    PlanLine,
    RepeatLine,
    SayLine,
    SkillLine,
    WaitLine,
)
from skill_server.plans.validation import check_plan
from skill_server.schema import SkillDescription
from skill_server.sequencer import Sequencer, attach_sequencer
from skill_server.sim.battery import BatterySpec
from skill_server.sim.robot_model import TELEBOT
from skill_server.sim.world import World
from skill_server.skills.base import Outcome, SkillController, TickInput
from skill_server.skills.catalog import default_registry
from skill_server.skills.registry import SkillRegistry


@pytest.fixture
def lab() -> Iterator[tuple[World, Sequencer]]:
    """The default lab (a wall 4 m ahead of the dock), stepped by the test, the test in control."""
    with World("lab", realtime=False, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        yield world, sequencer


def run(world: World, sequencer: Sequencer, *steps: PlanLine, limit_s: float = 120.0) -> GoalSnapshot:
    checked = check_plan(Plan("events", tuple(steps)), sequencer.registry, sequencer.spec)
    goal_id = sequencer.run_plan(TOKEN, checked, False).goal.goal_id
    goal = sequencer.goals.get(goal_id)
    assert goal is not None
    start_s = world.snapshot.sim_time_s
    while not goal.status.is_terminal and world.snapshot.sim_time_s - start_s < limit_s:
        world.step_for(0.1)
    return goal.snapshot()


def said(sequencer: Sequencer, final: GoalSnapshot, kind: EventKind = EventKind.STEP_STARTED) -> list[str]:
    goal = sequencer.goals.get(final.goal_id)
    assert goal is not None
    return [event.message for event in goal.events if event.kind is kind]


def test_an_obstacle_cuts_the_drive_short_and_the_on_block_backs_away(lab: tuple[World, Sequencer]) -> None:
    """Driving at a wall 4 m ahead: without the on the drive aborts COLLISION_AHEAD (test_plan_executor); with it
    the handler runs at the warning distance, before the collision guard, and the plan goes on to its end."""
    world, sequencer = lab
    final = run(world, sequencer,
                OnLine(1, 1, "obstacle_detected", 0.5, (SayLine(2, 3, "too close"), DriveLine(3, 3, -0.2, 0.0, 1.0))),
                DriveLine(5, 1, 0.4, 0.0, 30.0),
                SayLine(6, 1, "after the drive"))
    assert final.status is GoalStatus.SUCCEEDED, final.message
    handled = said(sequencer, final, EventKind.HANDLED)
    assert len(handled) == 1 and handled[0].startswith("line 5 cut short by obstacle_detected (obstacle 0.")
    assert handled[0].endswith("the on of line 1 runs")
    assert said(sequencer, final)[-3:] == ["line 2: too close", "line 3: drive -0.2 m/s 0 rad/s for 1 s",
                                           "line 6: after the drive"]
    wall_face_m, radius_m = 4.0, sequencer.spec.body_radius_m
    rim_gap_m = wall_face_m - (world.snapshot.ground_truth.x_m + radius_m)
    assert 0.5 < rim_gap_m < 1.0  # stopped near the warning distance, then backed away 0.2 m


def test_each_line_in_scope_is_cut_short_and_the_repeat_goes_on(lab: tuple[World, Sequencer]) -> None:
    """Handled inside a repeat: each turn's drive ends at the wall's warning distance and the repeat goes on; the
    watch fires again only after the way cleared (the handler backs off beyond it)."""
    world, sequencer = lab
    final = run(world, sequencer,
                RepeatLine(1, 1, 3, (
                    OnLine(2, 3, "obstacle_detected", 0.6, (DriveLine(3, 5, -0.3, 0.0, 2.0),)),
                    DriveLine(5, 3, 0.4, 0.0, 20.0))))
    assert final.status is GoalStatus.SUCCEEDED, final.message
    assert len(said(sequencer, final, EventKind.HANDLED)) == 3


def test_goal_reached_of_a_skill_line_runs_its_on_block(lab: tuple[World, Sequencer]) -> None:
    world, sequencer = lab
    final = run(world, sequencer,
                OnLine(1, 1, "goal_reached", 0.0, (SayLine(2, 3, "arrived"),)),
                SkillLine(4, 1, "go_to_goal", (("goal_x_m", 0.6), ("goal_y_m", 0.0))),
                SayLine(5, 1, "next"))
    assert final.status is GoalStatus.SUCCEEDED, final.message
    assert said(sequencer, final)[-2:] == ["line 2: arrived", "line 5: next"]


def test_battery_low_fires_at_once_when_the_charge_is_below_already() -> None:
    spec = replace(TELEBOT, battery=BatterySpec(initial_charge=0.15))
    with World("lab", realtime=False, deadman_timeout_s=1000.0, spec=spec) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        final = run(world, sequencer, OnLine(1, 1, "battery_low", 0.0, (SayLine(2, 3, "low battery"),)),
                    WaitLine(3, 1, None, 30.0))
        assert final.status is GoalStatus.SUCCEEDED, final.message
        assert said(sequencer, final)[-1] == "line 2: low battery"
        assert said(sequencer, final, EventKind.BATTERY_LOW) == ["battery at 15%, below 20% (the on of line 1)"]
        assert world.snapshot.sim_time_s < 2.0  # the 30 s wait was cut short


@pytest.mark.parametrize(("steps", "expected"), [
    ((OnLine(1, 1, "obstacle_spotted", 0.0, (SayLine(2, 3, "x"),)), SayLine(4, 1, "y")),
     (1, "event", "the event must be one of: obstacle_detected, wall_lost, goal_reached, localized, battery_low")),
    ((OnLine(1, 1, "wall_lost", 0.3, (SayLine(2, 3, "x"),)), SayLine(4, 1, "y")),
     (1, "value", "wall_lost takes no value")),
    ((OnLine(1, 1, "obstacle_detected", 9.0, (SayLine(2, 3, "x"),)), SayLine(4, 1, "y")),
     (1, "value", "value must be a finite number at least 0.05 and at most 3 m")),
    ((SayLine(1, 1, "y"), OnLine(2, 1, "goal_reached", 0.0, (SayLine(3, 3, "x"),))),
     (2, "on", "this on handles nothing")),
    ((OnLine(1, 1, "goal_reached", 0.0, (OnLine(2, 3, "wall_lost", 0.0, (SayLine(3, 5, "x"),)), SayLine(4, 3, "z"))),
      SayLine(6, 1, "y")),
     (2, "on", "an on block cannot hold another on")),
    ((OnLine(1, 1, "goal_reached", 0.0, (SayLine(2, 3, "x"),)),
      OnLine(4, 1, "goal_reached", 0.0, (SayLine(5, 3, "x"),)), SayLine(7, 1, "y")),
     (4, "event", "goal_reached is handled already on line 1 of this block")),
    ((OnLine(1, 1, "localized", 0.0, ()), SayLine(3, 1, "y")), (1, "body", "an on block needs at least one line")),
])
def test_an_on_that_cannot_work_is_refused_naming_its_line(lab: tuple[World, Sequencer], steps: tuple[PlanLine, ...],
                                                            expected: tuple[int, str, str]) -> None:
    _, sequencer = lab
    with pytest.raises(InvalidPlan) as refused:
        check_plan(Plan("bad", steps), sequencer.registry, sequencer.spec)
    line, field, message = expected
    assert any(e.line == line and e.field == field and e.message.startswith(message) for e in refused.value.errors), \
        refused.value.errors


def test_skills_name_their_class_of_the_2003_paper(lab: tuple[World, Sequencer]) -> None:
    _, sequencer = lab
    classes = {entry.description.name: entry.skill_class for entry in sequencer.registry.entries()}
    assert classes == {"direct_control": "motor", "go_to_goal": "sensorimotor", "orientation_control": "sensorimotor",
                       "wall_following": "sensorimotor", "round_trip": "sensorimotor",
                       "detect_obstacle": "perceptive", "environment_modelling": "deliberative",
                       "localization": "perceptive"}


class _ConvergesAfterASecond(SkillController):
    """A stand-in for the localization skill (which needs a map and a tour to converge): a perceptive goal that
    announces CONVERGED after 1 s of sim time, as localization does when its cloud is tight."""

    motor = False
    skill_class = "perceptive"

    def __init__(self) -> None:
        super().__init__()
        self._started_s: float | None = None

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        self._started_s = tick.sim_time_s if self._started_s is None else self._started_s
        if tick.sim_time_s - self._started_s >= 1.0 and not getattr(self, "_said", False):
            self._said = True
            self.announce(EventKind.CONVERGED, "converged at (0.00, 0.00) m")
        return 0.0, 0.0, None, GoalFeedback()


def test_localized_comes_from_a_goal_beside_the_plan_through_the_event_manager() -> None:
    registry = default_registry(TELEBOT)
    # localization's own name, so that the plan's check finds the skill its event comes from
    replaced = SkillRegistry()
    for entry in registry.entries():
        if entry.description.name == "localization":
            replaced.register(SkillDescription("localization", "Localization", "stand-in"), _ConvergesAfterASecond)
        else:
            replaced.register(entry.description, entry.skill, entry.build)
    with World("lab", realtime=False, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world, registry=replaced)
        world.set_controller(TOKEN)
        sequencer.activate(TOKEN, "localization", {}, False)
        final = run(world, sequencer, OnLine(1, 1, "localized", 0.0, (SayLine(2, 3, "I know where I am"),)),
                    WaitLine(4, 1, None, 30.0))
        assert final.status is GoalStatus.SUCCEEDED, final.message
        assert said(sequencer, final)[-1] == "line 2: I know where I am"
        assert said(sequencer, final, EventKind.HANDLED) == [
            "line 4 cut short by localized (localization: converged at (0.00, 0.00) m): the on of line 1 runs"]
        assert world.snapshot.sim_time_s < 3.0
