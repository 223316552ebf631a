"""Every error of the text form with its line, column and field, in a sentence a student understands; all the
problems of a plan found in one pass."""

from __future__ import annotations

import pytest

from middleware.plans import PlanError, PlanInvalid, parse_plan_text
from middleware.teaching.command_form import SkillSchemas

# (text, line, column, field, part of the message)
ERRORS = [
    ("go_to 120 0", 1, 7, "steps[0].parameters.goal_x_m",
     "line 1, column 7: goal_x_m must be between -50 and 50 m; got 120."),
    ("say \"ok\"\ngo_to 1 2 speed=2", 2, 17, "steps[1].parameters.speed_mps",
     "line 2, column 17: speed_mps must be between 0.05 and 0.5 m/s; got 2."),
    ("go_to 1 2 warp=9", 1, 11, "steps[0].parameters.warp", "go_to_goal has no parameter 'warp'"),
    ("go_to 1 2 sped=0.3", 1, 11, "steps[0].parameters.sped", "(did you mean speed_mps?)"),
    ("go_to 1 2 goal_x_m=3", 1, 11, "steps[0].parameters.goal_x_m", "goal_x_m is given twice"),
    ("go_to 99 2 goal_x_m=3", 1, 7, "steps[0].parameters.goal_x_m", "goal_x_m must be between -50 and 50 m; got 99."),
    ("go_to 1", 1, 1, "steps[0].parameters.goal_y_m", "go_to needs goal_y_m, as in go_to 1.2 0.5"),
    ("go_to 1 2 3", 1, 11, "steps[0]", "go_to takes at most 2 values without a name"),
    ("go_to speed=0.3 1 2", 1, 17, "steps[0]", "values without a name come first"),
    ("go_to 1 2 speed=", 1, 16, "steps[0]", "speed= needs a value"),
    ("go_to 1 2 = 3", 1, 11, "steps[0]", "= stands between a name and its value"),
    ("go_to 1 2 speed=fast", 1, 17, "steps[0].parameters.speed_mps", "speed_mps must be a number"),
    ("go_to 1.2.3 0", 1, 7, "text", "'1.2.3' is not a number"),
    ("go_to 1x 0", 1, 7, "steps[0].parameters.goal_x_m", "'x' is not a unit"),
    ("go_to 2s 0", 1, 7, "steps[0].parameters.goal_x_m", "goal_x_m is a distance in m; 2s is a time. Use m, cm."),
    ("turn_to 2m", 1, 9, "steps[0].parameters.heading_rad", "heading_rad is an angle in rad; 2m is a distance"),
    ("turn_to 400deg", 1, 9, "steps[0].parameters.heading_rad", "heading_rad must be between -3.14159 and 3.14159 "
                                                                "rad; got 400deg."),
    ("localization particle_count=2.5", 1, 29, "steps[0].parameters.particle_count", "must be a whole number"),
    ("localization particle_count=5m", 1, 29, "steps[0].parameters.particle_count", "takes a plain number"),
    ("environment_modelling use_sonar=1", 1, 33, "steps[0].parameters.use_sonar", "must be true or false"),
    ("follow_wall up 0.4", 1, 13, "steps[0].parameters.side", "side must be one of left, right; got up."),
    ("go_to_goal 1 2", 1, 12, "steps[0]", "go_to_goal takes its parameters as name=value"),
    ("teleport 1 2", 1, 1, "steps[0].skill", "'teleport' is not a command or a skill of this robot"),
    ("goto 1 2", 1, 1, "steps[0].skill", "(did you mean go_to?)"),
    ("go_to 1 2 for 0s", 1, 15, "steps[0].duration_s", "a duration must be more than 0 s and at most 600 s; got 0s"),
    ("go_to 1 2 for 11min", 1, 15, "steps[0].duration_s", "'min' is not a unit"),
    ("go_to 1 2 for 601s", 1, 15, "steps[0].duration_s", "got 601s"),
    ("go_to 1 2 for", 1, 11, "steps[0]", "for needs a time, as in for 20s"),
    ("go_to 1 2 for 2s for 3s", 1, 18, "steps[0]", "for is given twice"),
    ("drive 0.2 0", 1, 1, "steps[0]", "drive takes a speed, a turn rate and a time: drive 0.2 0 for 2s"),
    ("drive 2 0 for 1s", 1, 7, "steps[0].linear_mps", "linear_mps must be between -0.5 and 0.5 m/s; got 2."),
    ("drive 0 3 for 1s", 1, 9, "steps[0].angular_radps", "angular_radps must be between -1.5 and 1.5 rad/s"),
    ("drive 0.1 0 for fast", 1, 17, "steps[0].duration_s", "for needs a time"),
    ("wait", 1, 1, "steps[0]", "wait takes one time, as in wait 2s"),
    ("wait 2m", 1, 6, "steps[0].duration_s", "is a time in s; 2m is a distance"),
    ("wait_until", 1, 1, "steps[0].condition.kind", "wait_until needs a condition"),
    ("wait_until obstacle_within", 1, 12, "steps[0].condition.value", "obstacle_within needs a value"),
    ("wait_until obstacle_within 20", 1, 28, "steps[0].condition.value", "between 0.05 and 8 m; got 20."),
    ("wait_until goal_reached 1", 1, 25, "steps[0].condition.value", "goal_reached takes no value"),
    ("wait_until battery_below 2", 1, 26, "steps[0].condition.value",
     "battery_below must be between 0.01 and 1; got 2."),
    ("wait_until obstacle 0.5", 1, 12, "steps[0].condition.kind", "'obstacle' is not a condition"),
    ("wait_until goal_reached timeout 0s", 1, 33, "steps[0].duration_s", "more than 0 s"),
    ("wait_until goal_reached speed=1", 1, 25, "steps[0]", "wait_until takes a condition and maybe a timeout"),
    ("set max_speed 2", 1, 15, "steps[0].value", "max_speed must be between 0.05 and 0.5 m/s; got 2."),
    ("set watchdog 0.5m", 1, 14, "steps[0].value", "watchdog is a time in s"),
    # the base's drive watchdog: the range SetLimits accepts (README, Low-level commands)
    ("set watchdog 0.1s", 1, 14, "steps[0].value", "watchdog must be between 0.2 and 5 s; got 0.1s."),
    ("set watchdog 6s", 1, 14, "steps[0].value", "watchdog must be between 0.2 and 5 s; got 6s."),
    ("set turbo 1", 1, 5, "steps[0].setting", "'turbo' is not a setting"),
    ("set max_speed", 1, 1, "steps[0]", "set takes a setting and a value"),
    ("say hello", 1, 5, "steps[0].text", 'say takes one text in double quotes: say "hello".'),
    ("say \"\"", 1, 5, "steps[0].text", "say needs some text"),
    ("say \"" + "a" * 201 + "\"", 1, 5, "steps[0].text", "at most 200 characters; this one has 201"),
    ("say 'hi'", 1, 5, "text", "texts are written in double quotes"),
    ("say \"hi", 1, 5, "text", 'this text has no closing " on its line'),
    ("say \"a\\nb\"", 1, 7, "text", 'in a text, \\ may only come before " or \\'),
    ("repeat 0 {\n  say \"x\"\n}", 1, 8, "steps[0].count", "count must be between 1 and 100; got 0."),
    ("repeat 101 {\n  say \"x\"\n}", 1, 8, "steps[0].count", "got 101"),
    ("repeat 2.5 {\n  say \"x\"\n}", 1, 8, "steps[0].count", "count must be a whole number"),
    ("repeat {\n  say \"x\"\n}", 1, 1, "steps[0].count", "repeat takes one count and a block"),
    ("repeat 2\nsay \"x\"", 1, 1, "steps[0].body", "repeat needs a block: repeat ... { commands }"),
    ("repeat 2 {\n}", 1, 1, "steps[0].body", "this repeat has nothing in its block"),
    ("repeat 2 {\n  say \"x\"\n", 1, 10, "steps[0].body", "this { is never closed; end its block with }."),
    ("say \"x\"\n}", 2, 1, "steps", "this } closes no block; remove it."),
    ("{\n  say \"x\"\n}", 1, 1, "steps[0]", "a { block } belongs after repeat, if, else or on"),
    ("say \"x\" {\n}", 1, 9, "steps[0]", "only repeat, if, else and on take a { block }"),
    ("repeat 2 { say \"x\" } say \"y\"", 1, 22, "steps[0].body", "start the next command on a new line"),
    ("else {\n}", 1, 1, "steps[0]", "else must follow the } of an if"),
    ("if {\n}", 1, 1, "steps[0].condition.kind", "if needs a condition"),
    ("if goal_reached {\n} else goal_reached {\n}", 2, 8, "steps[0].else", "else takes no condition"),
    ("if obstacle_within 0.5 0.6 {\n}", 1, 24, "steps[0].condition.value", "takes at most one value"),
    ("if not not goal_reached {\n}", 1, 8, "steps[0].condition.kind", "'not' is not a condition"),
    ("gö_to 1 2", 1, 1, "text", "'gö_to': names use the letters a-z, digits and _ only"),
    ("say \"a\" ; say \"b\"", 1, 9, "text", "';' has no meaning here"),
    ("say \"a\x00b\"", 1, 7, "text", "in a text, the invisible character U+0000 is not allowed"),
    ("say \"abc\u202e\"", 1, 9, "text", "U+202E is not allowed"),
    ("say \"a\tb\"", 1, 7, "text", "a tab is not allowed; write spaces"),
    ("say \"a\" # \x07", 1, 11, "text", "in a comment, the invisible character U+0007"),
    ("turn_to 90 deg", 1, 12, "steps[0]", "write a unit against its number, without a space: 90deg."),
    ("wait 2 s", 1, 8, "steps[0]", "write a unit against its number, without a space: 2s."),
    ("if obstacle_within 50 cm {\n}", 1, 23, "steps[0].condition", "without a space: 50cm."),
    ("set watchdog 500 ms", 1, 18, "steps[0]", "without a space: 500ms."),
    ("go_to 1,5 0", 1, 8, "text", "decimals written with a point (go_to 1.5 0.5)"),
    ("go to 1 2", 1, 1, "steps[0].skill",
     "'go' is not a command or a skill of this robot (did you mean go_to, with _?)"),
    ("Go_To 1 2", 1, 1, "steps[0].skill", "(did you mean go_to? names are written in lower case)"),
]


@pytest.mark.parametrize(("text", "line", "column", "field", "message"), ERRORS, ids=[e[0][:30] for e in ERRORS])
def test_each_error_names_its_line_column_and_field(skills: SkillSchemas, text: str, line: int, column: int,
                                                   field: str, message: str) -> None:
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text(text, skills)
    first = refused.value.errors[0]
    assert (first.line, first.column, first.field) == (line, column, field), first
    assert message in first.message
    assert first.message.startswith(f"line {line}, column {column}: ")
    assert refused.value.status == 400 and refused.value.code == "invalid_plan" and refused.value.field == field


def test_every_bad_line_is_reported_in_one_pass(skills: SkillSchemas) -> None:
    text = ("go_to 120 0\n"
            "say \"fine\"\n"
            "repeat 2 {\n"
            "  drive 9 0 for 1s\n"
            "  teleport\n"
            "}\n"
            "set max_speed 0.2\n"
            "turn_to 1m\n"
            "go_to 1 2 speed=9 tolerance=3\n")
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text(text, skills)
    assert [(e.line, e.column, e.field) for e in refused.value.errors] == [
        (1, 7, "steps[0].parameters.goal_x_m"),
        (4, 9, "steps[2].body[0].linear_mps"),
        (5, 3, "steps[2].body[1].skill"),
        (8, 9, "steps[4].parameters.heading_rad"),
        (9, 17, "steps[5].parameters.speed_mps"),
        (9, 29, "steps[5].parameters.max_error_m"),
    ]
    assert refused.value.message.endswith("(and 5 more problems)")
    body = refused.value.to_dict()
    assert body["error"] == {"code": "invalid_plan", "message": refused.value.message,
                             "field": "steps[0].parameters.goal_x_m"}
    assert body["errors"][0] == {"line": 1, "column": 7, "field": "steps[0].parameters.goal_x_m",
                                 "message": "line 1, column 7: goal_x_m must be between -50 and 50 m; got 120."}


def test_a_parameter_given_twice_is_named_even_when_its_first_value_was_wrong(skills: SkillSchemas) -> None:
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text("go_to 99 2 goal_x_m=3", skills)
    assert [(e.column, e.field) for e in refused.value.errors] == [
        (7, "steps[0].parameters.goal_x_m"), (12, "steps[0].parameters.goal_x_m")]
    assert "goal_x_m is given twice" in refused.value.errors[1].message


def test_errors_come_in_reading_order_whoever_found_them(skills: SkillSchemas) -> None:
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text("go_to 99 0\nsay 'x'\nturn_to 9\ngo_to 1 ;", skills)
    assert [(e.line, e.column) for e in refused.value.errors] == [(1, 7), (2, 5), (2, 7), (3, 9), (4, 9)]
    assert refused.value.field == "steps[0].parameters.goal_x_m"


def test_a_bad_block_header_still_has_its_block_checked(skills: SkillSchemas) -> None:
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text("repeat many {\n  go_to 99 0\n}\nif obstacle_within 99 {\n  say 3\n}", skills)
    assert [(e.line, e.field) for e in refused.value.errors] == [
        (1, "steps[0].count"), (2, "steps[0].body[0].parameters.goal_x_m"), (4, "steps[1].condition.value"),
        (5, "steps[1].then[0].text")]


def test_a_skill_the_robot_lacks_is_named(skills: SkillSchemas) -> None:
    fewer = {name: schema for name, schema in skills.items() if name != "orientation_control"}
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text("turn_to 90deg", fewer)
    assert refused.value.errors == (PlanError(1, 1, "steps[0].skill", "line 1, column 1: turn_to needs the skill "
                                              "orientation_control, which this robot does not have."),)


def test_an_empty_plan_is_refused(skills: SkillSchemas) -> None:
    for text in ("", "\n\n", "# only a comment\n", "\ufeff"):
        with pytest.raises(PlanInvalid) as refused:
            parse_plan_text(text, skills)
        assert refused.value.field == "steps"
        assert "the plan is empty" in refused.value.message
