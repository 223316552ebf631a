"""A plan is checked before anything moves: every fault named by line, column and field, all found at once."""

from __future__ import annotations

import math

import pytest

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
from skill_server.plans.validation import MAX_DEPTH, check_plan, robot_has_battery
from skill_server.sim.robot_model import TELEBOT
from skill_server.skills.catalog import default_registry

REGISTRY = default_registry(TELEBOT)


def check(*steps: PlanLine, name: str = "test-plan") -> Plan:
    return check_plan(Plan(name, tuple(steps)), REGISTRY, TELEBOT).plan


def faults(*steps: PlanLine, name: str = "test-plan") -> list[str]:
    with pytest.raises(InvalidPlan) as refused:
        check(*steps, name=name)
    return [str(error) for error in refused.value.errors]


def nested(depth: int) -> PlanLine:
    line: PlanLine = SayLine(depth + 1, 2 * depth + 1, "deep")
    for level in range(depth, 0, -1):
        line = RepeatLine(level, 2 * level - 1, 1, (line,))
    return line


def test_a_skill_step_gets_its_defaults_and_its_parameters_checked() -> None:
    plan = check(SkillLine(1, 1, "go_to_goal", (("goal_x_m", 1.2), ("goal_y_m", 0.5))))
    step = plan.steps[0]
    assert isinstance(step, SkillLine)
    assert dict(step.parameters)["goal_x_m"] == 1.2 and dict(step.parameters)["speed_mps"] == 0.3


def test_every_construct_passes_when_well_formed() -> None:
    condition = PlanCondition("obstacle_within", 0.5)
    checked = check_plan(Plan("all_kinds", (
        SetLine(1, 1, "max_speed", 0.3), SetLine(2, 1, "watchdog", 5.0), SayLine(3, 1, "hello"),
        DriveLine(4, 1, 0.2, 0.0, 2.0), WaitLine(5, 1, None, 1.0),
        WaitLine(6, 1, PlanCondition("goal_reached", negate=True), 3.0),
        RepeatLine(7, 1, 3, (SkillLine(8, 3, "orientation_control", (("heading_rad", 1.0),)),)),
        IfLine(9, 1, condition, (SayLine(10, 3, "near"),), (SayLine(12, 3, "far"),)),
    )), REGISTRY, TELEBOT)
    assert checked.expanded_steps == 6 + 3 + 3 and checked.skills == ("orientation_control",)


@pytest.mark.parametrize(("step", "expected"), [
    (SkillLine(3, 5, "fly", ()), "line 3, column 5: skill: unknown skill 'fly'"),
    (SkillLine(2, 1, "go_to_goal", (("goal_x_m", 99.0),)), "line 2, column 1: goal_x_m: goal_x_m must be"),
    (SkillLine(2, 1, "go_to_goal", (("goal_x_m", math.nan),)), "line 2, column 1: goal_x_m:"),
    (SkillLine(2, 1, "go_to_goal", (("colour", 1.0),)), "line 2, column 1: colour: colour is not a parameter"),
    (SkillLine(4, 1, "detect_obstacle", ()), "line 4, column 1: skill: detect_obstacle is a perceptive skill"),
    (SkillLine(4, 1, "wall_following", (), math.inf), "line 4, column 1: duration_s:"),
    (DriveLine(5, 1, math.nan, 0.0, 1.0), "line 5, column 1: linear_mps:"),
    (DriveLine(5, 1, 0.1, 9.0, 1.0), "line 5, column 1: angular_radps:"),
    (DriveLine(5, 1, 0.1, 0.0, 0.0), "line 5, column 1: duration_s:"),
    (DriveLine(5, 1, 0.1, 0.0, 601.0), "line 5, column 1: duration_s:"),
    (WaitLine(6, 2, None, 0.0), "line 6, column 2: duration_s: a wait needs"),
    (WaitLine(6, 2, PlanCondition("raining"), 0.0), "line 6, column 2: condition.kind:"),
    (WaitLine(6, 2, PlanCondition("obstacle_within", -1.0), 0.0), "line 6, column 2: condition.value:"),
    (RepeatLine(7, 1, 1000, (SayLine(8, 1, "x"),)), "line 7, column 1: count: count must be an integer"),
    (RepeatLine(7, 1, 0, (SayLine(8, 1, "x"),)), "line 7, column 1: count:"),
    (IfLine(9, 1, None, ()), "line 9, column 1: condition: an if needs a condition"),
    (SetLine(10, 1, "colour", 1.0), "line 10, column 1: setting:"),
    (SetLine(10, 1, "max_speed", 5.0), "line 10, column 1: value: value must be a finite number above 0"),
    (SetLine(10, 1, "watchdog", math.inf), "line 10, column 1: value:"),
    (SayLine(11, 1, "x" * 201), "line 11, column 1: text: say at most 200 characters"),
    (SayLine(11, 1, "two\nlines"), "line 11, column 1: text:"),
])
def test_each_fault_names_its_line_column_and_field(step: PlanLine, expected: str) -> None:
    assert faults(step)[0].startswith(expected)


def test_every_fault_is_found_at_once_inside_blocks_too() -> None:
    found = faults(
        SayLine(1, 1, "fine"),
        RepeatLine(2, 1, 2, (DriveLine(3, 3, 0.1, 0.0, -1.0), SkillLine(4, 3, "go_to_goal", (("goal_y_m", 80.0),)))),
        IfLine(5, 1, PlanCondition("obstacle_within", 0.5), (), (SkillLine(7, 3, "teleport", ()),)),
    )
    assert [fault.split(":")[0] for fault in found] == ["line 3, column 3", "line 4, column 3", "line 7, column 3"]


def test_nesting_is_limited_to_eight_blocks() -> None:
    check(nested(MAX_DEPTH))
    assert faults(nested(MAX_DEPTH + 1)) == [f"line 9, column 17: depth: blocks nest at most {MAX_DEPTH} deep"]


def test_a_plan_that_expands_past_ten_thousand_steps_is_refused() -> None:
    body = (SayLine(3, 5, "x"),) * 2
    plan = RepeatLine(1, 1, 100, (RepeatLine(2, 3, 100, body),))
    assert "the plan expands to 20000 steps" in faults(plan)[0]


@pytest.mark.parametrize("name", ["", "with space", "x" * 65, "semi;colon", "new\nline", "ünï"])
def test_the_plan_name_is_letters_digits_dash_and_underscore(name: str) -> None:
    assert faults(SayLine(1, 1, "hi"), name=name)[0].startswith("name: ")


def test_an_empty_plan_is_refused() -> None:
    assert faults()[0].startswith("steps: ")


def test_battery_below_is_refused_while_the_robot_reports_no_battery() -> None:
    step = WaitLine(1, 1, PlanCondition("battery_below", 0.2), 5.0)
    if robot_has_battery():
        check(step)
    else:
        assert "reports no battery" in faults(step)[0]


def test_the_refusal_is_an_invalid_parameter_naming_the_first_field() -> None:
    with pytest.raises(InvalidPlan) as refused:
        check(SayLine(1, 1, "ok"), DriveLine(2, 4, 0.1, 0.0, math.nan))
    assert refused.value.field == "duration_s"
    assert str(refused.value).startswith("invalid plan: line 2, column 4: duration_s: ")
