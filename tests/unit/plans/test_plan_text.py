"""The plan's text form: every construct read into steps, units converted, aliases resolved, and written back."""

from __future__ import annotations

import math

import pytest

from middleware.plans import (
    Condition,
    DriveStep,
    IfStep,
    Plan,
    RepeatStep,
    SayStep,
    SetStep,
    SkillStep,
    WaitStep,
    is_plan_name,
    parse_plan_text,
    plan_from_json,
    plan_summary,
    plan_to_json,
    plan_to_text,
)
from middleware.teaching.command_form import SkillSchemas

EVERY_CONSTRUCT = """# a patrol that uses every command
go_to 1.2 0.5 speed=0.3
turn_to 90deg
follow_wall left 0.4 for 20s
drive 0.2 0 for 2s
wait 2s
wait_until goal_reached
wait_until not obstacle_within 0.5 timeout 10s
repeat 3 {
  say "lap"   # a comment after a command
  if obstacle_within 50cm {
    drive -0.1 0 for 500ms
  } else {
    set max_speed 0.3
  }
}
set max_turn_rate 1
set watchdog 0.5s
say "done, \\"all\\" \\\\ fine"
go_to_goal goal_x_m=-1 goal_y_m=2 timeout_s=60 for 30s
if battery_below 0.2 {
  say "low"
}
"""


def test_every_construct_is_read_into_its_step_with_its_line_and_column(skills: SkillSchemas) -> None:
    plan = parse_plan_text(EVERY_CONSTRUCT, skills)
    assert plan.steps == (
        SkillStep("go_to_goal", (("goal_x_m", 1.2), ("goal_y_m", 0.5), ("speed_mps", 0.3))),
        SkillStep("orientation_control", (("heading_rad", math.pi / 2),)),
        SkillStep("wall_following", (("side", "left"), ("distance_m", 0.4)), 20.0),
        DriveStep(0.2, 0.0, 2.0),
        WaitStep(None, 2.0),
        WaitStep(Condition("goal_reached", None, False), None),
        WaitStep(Condition("obstacle_within", 0.5, True), 10.0),
        RepeatStep(3, (
            SayStep("lap"),
            IfStep(Condition("obstacle_within", 0.5), (DriveStep(-0.1, 0.0, 0.5),), (SetStep("max_speed", 0.3),)),
        )),
        SetStep("max_turn_rate", 1.0),
        SetStep("watchdog", 0.5),
        SayStep('done, "all" \\ fine'),
        SkillStep("go_to_goal", (("goal_x_m", -1.0), ("goal_y_m", 2.0), ("timeout_s", 60.0)), 30.0),
        IfStep(Condition("battery_below", 0.2), (SayStep("low"),)),
    )
    repeat = plan.steps[7]
    assert isinstance(repeat, RepeatStep)
    inner_if = repeat.body[1]
    assert isinstance(inner_if, IfStep)
    assert [(s.line, s.column) for s in plan.steps] == [
        (2, 1), (3, 1), (4, 1), (5, 1), (6, 1), (7, 1), (8, 1), (9, 1), (17, 1), (18, 1), (19, 1), (20, 1), (21, 1)]
    assert [(s.line, s.column) for s in repeat.body] == [(10, 3), (11, 3)]
    assert [(s.line, s.column) for s in (*inner_if.then, *inner_if.otherwise)] == [(12, 5), (14, 5)]


def test_the_canonical_json_form_is_the_agreed_one(skills: SkillSchemas) -> None:
    plan = parse_plan_text('go_to 1.2 0.5\ndrive 0.2 0 for 2s\nwait_until not obstacle_within 0.5 timeout 5s\n'
                           'repeat 3 {\n  say "hi"\n}\nif goal_reached {\n} else {\n  set max_speed 0.3\n}\n', skills)
    assert plan_to_json(plan) == {"format": "telelab-plan/1", "steps": [
        {"line": 1, "column": 1, "kind": "skill", "skill": "go_to_goal",
         "parameters": {"goal_x_m": 1.2, "goal_y_m": 0.5}, "duration_s": None},
        {"line": 2, "column": 1, "kind": "drive", "linear_mps": 0.2, "angular_radps": 0.0, "duration_s": 2.0},
        {"line": 3, "column": 1, "kind": "wait", "condition": {"kind": "obstacle_within", "value": 0.5,
                                                               "negate": True}, "duration_s": 5.0},
        {"line": 4, "column": 1, "kind": "repeat", "count": 3,
         "body": [{"line": 5, "column": 3, "kind": "say", "text": "hi"}]},
        {"line": 7, "column": 1, "kind": "if", "condition": {"kind": "goal_reached", "value": None, "negate": False},
         "then": [], "else": [{"line": 9, "column": 3, "kind": "set", "setting": "max_speed", "value": 0.3}]},
    ]}


@pytest.mark.parametrize(("written", "heading_rad"), [
    ("90deg", math.pi / 2), ("-45deg", -math.pi / 4), ("1.5rad", 1.5), ("1.5", 1.5), ("180deg", math.pi),
])
def test_angles_take_degrees_or_radians(skills: SkillSchemas, written: str, heading_rad: float) -> None:
    (step,) = parse_plan_text(f"turn_to {written}", skills).steps
    assert isinstance(step, SkillStep)
    assert step.parameters == (("heading_rad", pytest.approx(heading_rad, abs=1e-15)),)


@pytest.mark.parametrize(("text", "expected"), [
    ("go_to 120cm 50cm", (("goal_x_m", 1.2), ("goal_y_m", 0.5))),
    ("go_to 1 2 speed=0.3m/s", (("goal_x_m", 1.0), ("goal_y_m", 2.0), ("speed_mps", 0.3))),
    ("go_to 1 2 tolerance=5cm timeout=2s", (("goal_x_m", 1.0), ("goal_y_m", 2.0), ("max_error_m", 0.05),
                                            ("timeout_s", 2.0))),
    ("go_to 1 2 timeout=1500ms", (("goal_x_m", 1.0), ("goal_y_m", 2.0), ("timeout_s", 1.5))),
    ("turn_to 0 max_turn_rate=30deg/s", (("heading_rad", 0.0), ("max_angular_radps", math.radians(30)))),
    ("follow_wall right", (("side", "right"),)),
    ("follow_wall left distance=30cm speed=0.2", (("side", "left"), ("distance_m", 0.3), ("speed_mps", 0.2))),
    ("localization particle_count=500 initial_x_m=1e-1", (("particle_count", 500), ("initial_x_m", 0.1))),
    ('environment_modelling use_sonar=false restart=true', (("use_sonar", False), ("restart", True))),
    ('wall_following side="left"', (("side", "left"),)),
])
def test_units_aliases_and_short_keys_name_the_real_parameters(skills: SkillSchemas, text: str,
                                                               expected: tuple[tuple[str, object], ...]) -> None:
    (step,) = parse_plan_text(text, skills).steps
    assert isinstance(step, SkillStep)
    assert step.parameters == expected
    assert [type(v) for _, v in step.parameters] == [type(v) for _, v in expected]


@pytest.mark.parametrize("text", [
    "\ufeffsay \"bom\"\r\ndrive 0.1 0 for 1s\r\n",  # a byte order mark and Windows line ends
    "say \"old mac\"\rdrive 0.1 0 for 1s",
    "\tsay \"bom\"\n\tdrive\t0.1\t0\tfor\t1s\n",  # tabs between words
    "say \"bom\"\n\n\n   \n# nothing\ndrive 0.1 0 for 1s",
])
def test_line_ends_tabs_blank_lines_and_a_byte_order_mark_are_read(skills: SkillSchemas, text: str) -> None:
    steps = parse_plan_text(text, skills).steps
    assert [type(s) for s in steps] == [SayStep, DriveStep]
    assert steps[0].column in (1, 2)  # a tab counts as one character


def test_a_block_may_open_on_the_next_line_and_else_may_follow_on_its_own_line(skills: SkillSchemas) -> None:
    plan = parse_plan_text("repeat 2\n{\n  say \"a\"\n}\nif goal_reached\n{\n  say \"b\"\n}\nelse\n{\n  say \"c\"\n}",
                           skills)
    assert plan.steps == (RepeatStep(2, (SayStep("a"),)), IfStep(Condition("goal_reached"), (SayStep("b"),),
                                                                  (SayStep("c"),)))


def test_blocks_fit_on_one_line(skills: SkillSchemas) -> None:
    plan = parse_plan_text('repeat 2 { say "a" }\nif goal_reached { say "b" } else { say "c" }', skills)
    assert plan.steps == (RepeatStep(2, (SayStep("a"),)), IfStep(Condition("goal_reached"), (SayStep("b"),),
                                                                  (SayStep("c"),)))


def test_unicode_stands_in_texts_and_comments(skills: SkillSchemas) -> None:
    plan = parse_plan_text('# ロボット, größer\nsay "héllo wörld 🤖 — ok"', skills)
    assert plan.steps == (SayStep("héllo wörld 🤖 — ok"),)


def test_eight_nested_blocks_are_allowed(skills: SkillSchemas) -> None:
    text = "".join(f"{'  ' * d}repeat 2 {{\n" for d in range(8)) + "  " * 8 + "say \"deep\"\n" + \
        "".join(f"{'  ' * d}}}\n" for d in reversed(range(8)))
    plan = parse_plan_text(text, skills)
    assert plan_summary(plan)["steps"] == 2 ** 8


def test_the_summary_counts_steps_bounds_the_time_and_names_the_skills(skills: SkillSchemas) -> None:
    plan = parse_plan_text("repeat 3 {\n  drive 0.1 0 for 2s\n  go_to 1 0 for 10s\n}\nif goal_reached {\n"
                           "  wait 5s\n} else {\n  turn_to 0 timeout=3\n}\nsay \"x\"\n", skills)
    assert plan_summary(plan) == {"steps": 3 * 2 + 1 + 1 + 1 + 1, "max_duration_s": 3 * 12.0 + 5.0,
                                  "skills": ["go_to_goal", "orientation_control"]}
    unbounded = parse_plan_text("go_to 1 0\nwait_until goal_reached", skills)
    assert plan_summary(unbounded)["max_duration_s"] is None


def test_the_written_text_reads_back_to_an_equal_plan_and_json_too(skills: SkillSchemas) -> None:
    plan = parse_plan_text(EVERY_CONSTRUCT, skills)
    text = plan_to_text(plan)
    assert parse_plan_text(text, skills) == plan
    assert plan_to_text(parse_plan_text(text, skills)) == text
    assert plan_to_json(plan_from_json(plan_to_json(plan), skills)) == plan_to_json(plan)


def test_the_written_text_uses_the_short_commands_and_degrees(skills: SkillSchemas) -> None:
    plan = parse_plan_text("go_to 1.2 0.5 speed=0.3\nturn_to 90deg\nfollow_wall left 0.4 for 20s\n"
                           "go_to_goal goal_y_m=1 goal_x_m=2\nif not obstacle_within 0.5 {\n  wait 2s\n}\n"
                           "set watchdog 500ms\nsay \"a \\\"b\\\"\"", skills)
    assert plan_to_text(plan) == ("go_to 1.2 0.5 speed_mps=0.3\nturn_to 90deg\nfollow_wall left 0.4 for 20s\n"
                                  "go_to_goal goal_y_m=1 goal_x_m=2\nif not obstacle_within 0.5 {\n  wait 2s\n}\n"
                                  "set watchdog 0.5s\nsay \"a \\\"b\\\"\"\n")


def test_the_summary_bound_is_not_float_noise(skills: SkillSchemas) -> None:
    plan = parse_plan_text("repeat 4 {\n  drive 0.2 0 for 2s\n  drive 0 0.5 for 3.14s\n}", skills)
    assert plan_summary(plan)["max_duration_s"] == 20.56


@pytest.mark.parametrize(("name", "valid"), [
    ("patrol", True), ("Lap-2_b", True), ("a" * 64, True), ("", False), ("a" * 65, False), ("two words", False),
    ("plan:x", False), ("é", False), ("１", False), ("../x", False), (None, False), (7, False),
])
def test_a_plan_name_is_letters_digits_dash_and_underscore(name: object, valid: bool) -> None:
    assert is_plan_name(name) is valid


def test_plans_compare_by_what_they_do_not_where_they_were_written(skills: SkillSchemas) -> None:
    assert parse_plan_text("say \"a\"", skills) == parse_plan_text("\n\n   say \"a\"", skills) == \
        Plan((SayStep("a"),))
