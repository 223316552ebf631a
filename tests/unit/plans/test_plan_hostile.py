"""Hostile plans, as text and as JSON: each refused with a clear error that names where, never another exception,
and quickly (a megabyte is refused before it is read)."""

from __future__ import annotations

import contextlib
import json
import math
import time

import pytest

from middleware.plans import PlanInvalid, parse_plan_text, plan_from_json
from middleware.teaching.command_form import SkillSchemas


def nested(depth: int, inner: str = 'say "deep"') -> str:
    """repeat blocks depth deep around inner."""
    return "".join("repeat 2 {\n" for _ in range(depth)) + inner + "\n" + "}\n" * depth


HOSTILE_TEXTS = [
    ("nine nested blocks", nested(9), 9, 10, "steps[0]" + ".body[0]" * 8 + ".body",
     "blocks nest at most 8 deep; this one would be 9 deep"),
    ("ten thousand braces", "{" * 10_000, 1, 1, "steps[0]", "a { block } belongs after repeat, if, else or on"),
    ("ten thousand closing braces", "}" * 10_000, 1, 1, "steps", "this } closes no block"),
    ("repeat a billion", 'repeat 1000000000 {\n  say "x"\n}', 1, 8, "steps[0].count",
     "count must be between 1 and 100; got 1000000000."),
    ("repeat 10**9 written long", 'repeat 1e9 {\n  say "x"\n}', 1, 8, "steps[0].count", "got 1e9"),
    ("a count of 5000 digits", "repeat " + "9" * 5000 + ' {\n  say "x"\n}', 1, 8, "steps[0].count",
     "count must be a finite number; got 9999"),
    ("nan as a word", "go_to nan 0", 1, 7, "steps[0].parameters.goal_x_m", "goal_x_m must be a number; got nan."),
    ("inf as a word", "go_to 0 inf", 1, 9, "steps[0].parameters.goal_y_m", "goal_y_m must be a number; got inf."),
    ("an overflowing number", "go_to 1e999 0", 1, 7, "steps[0].parameters.goal_x_m", "must be a finite number"),
    ("a number of 60 000 digits", "go_to " + "9" * 60_000 + " 0", 1, 7, "steps[0].parameters.goal_x_m",
     "must be a finite number; got 9999999999999999999999999999999999999..."),
    ("an unknown skill", "self_destruct now=true", 1, 1, "steps[0].skill", "'self_destruct' is not a command"),
    ("code instead of a plan", "__import__('os').system('rm -rf /')", 1, 11, "text", "'(' has no meaning here"),
    ("html", "<script>alert(1)</script>", 1, 1, "text", "'<' has no meaning here"),
    ("an unterminated block", "repeat 3 {\n  say \"a\"\n  repeat 2 {\n    say \"b\"\n  }\n", 1, 10, "steps[0].body",
     "this { is never closed"),
    ("an unterminated text", 'say "never closed\nsay "b"', 1, 5, "text", 'this text has no closing "'),
    ("a lone surrogate", 'say "\ud800"', 1, 6, "text", "U+D800 is not allowed"),
    ("a NUL in a command", "go_to\x001 2", 1, 6, "text", "U+0000 is not allowed"),
    ("a byte order mark inside", "say \"a\"\n\ufeffsay \"b\"", 2, 1, "text", "'\\ufeff' has no meaning here"),
    ("a unicode identifier", "ходить 1 2", 1, 1, "text", "names use the letters a-z, digits and _ only"),
    ("a fullwidth digit", "go_to １ 2", 1, 7, "text", "names use the letters a-z"),
    ("a vertical tab", "say \"a\"\x0bsay \"b\"", 1, 8, "text", "U+000B is not allowed"),
    ("a line separator", "say \"a\"\u2028say \"b\"", 1, 8, "text", "U+2028 is not allowed"),
    ("steps multiplied past 10 000", "repeat 100 {\n  repeat 100 {\n    say \"x\"\n    say \"y\"\n  }\n}", 1, 1,
     "steps[0]",
     "more than 10,000 steps"),
    ("drives past 1 800 s", "repeat 4 {\n  drive 0.1 0 for 500s\n}\n", 1, 1, "steps[0]",
     "takes at least 2,000 s of drives and waits; a plan may run at most 1,800 s"),
]


@pytest.mark.parametrize(("name", "text", "line", "column", "field", "message"), HOSTILE_TEXTS,
                         ids=[h[0] for h in HOSTILE_TEXTS])
def test_a_hostile_text_is_refused_with_its_place(skills: SkillSchemas, name: str, text: str, line: int, column: int,
                                                  field: str, message: str) -> None:
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text(text, skills)
    first = refused.value.errors[0]
    assert (first.line, first.column, first.field) == (line, column, field), first
    assert message in first.message, first.message
    assert len(refused.value.errors) <= 50


def test_a_megabyte_is_refused_before_it_is_read(skills: SkillSchemas) -> None:
    for text in ("say \"x\"\n" * 150_000, "(" * 1_048_576, "é" * 40_000, "\ud800" * 70_000):
        with pytest.raises(PlanInvalid) as refused:
            parse_plan_text(text, skills)
        assert len(refused.value.errors) == 1  # read, "(" alone would be 50 errors
        assert refused.value.field == "text"
        assert "a plan has at most 65,536 bytes (UTF-8)" in refused.value.message


def test_more_than_500_lines_are_refused_before_they_are_read(skills: SkillSchemas) -> None:
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text("\n" * 501 + "say \"late\"", skills)
    assert refused.value.message == "text: the plan has 502 lines; a plan has at most 500 lines."
    assert len(parse_plan_text("say \"x\"\n" * 500, skills).steps) == 500


def test_the_worst_text_within_the_size_limit_is_read_in_one_linear_pass(skills: SkillSchemas) -> None:
    worst = [("say \"" + "\\\"" * 30 + "\"\n") * 400, ("go_to 1 2 " + "speed=0.3 " * 600 + "\n") * 10,
             ("(" * 120 + "\n") * 500, "repeat 2 { " * 5000, "go_to 1 2 " + "x=1 " * 16_000,
             "if not obstacle_within 0.5 { say \"x\" } else { say \"y\" }\n" * 400]
    for text in worst:
        started = time.perf_counter()
        with contextlib.suppress(PlanInvalid):
            parse_plan_text(text[:65_000], skills)
        # a guard against reading that grows faster than the text, not a benchmark: unloaded, each takes < 0.3 s
        assert time.perf_counter() - started < 10.0
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text("(" * 65_000, skills)
    assert len(refused.value.errors) == 50
    assert refused.value.errors[-1].column == 50  # reading stopped at the fiftieth problem


def test_anything_but_a_string_is_refused_as_text(skills: SkillSchemas) -> None:
    for value in (None, b"say", 3, ["say"]):
        with pytest.raises(PlanInvalid) as refused:
            parse_plan_text(value, skills)  # type: ignore[arg-type]
        assert refused.value.field == "text"


def step(**fields: object) -> dict[str, object]:
    """A plan of one step."""
    return {"format": "telelab-plan/1", "steps": [fields]}


DRIVE = {"kind": "drive", "linear_mps": 0.1, "angular_radps": 0.0, "duration_s": 1.0}
HOSTILE_JSON = [
    ("a list", [], "plan", "a plan is a JSON object"),
    ("null", None, "plan", "a plan is a JSON object"),
    ("a string", "say hi", "plan", "a plan is a JSON object"),
    ("no steps", {"format": "telelab-plan/1"}, "steps", "a plan needs its steps"),
    ("steps not a list", {"steps": {"0": DRIVE}}, "steps", "steps must be a list of steps; got an object."),
    ("a wrong format", {"format": "telelab-plan/2", "steps": [DRIVE]}, "format", "format must be 'telelab-plan/1'"),
    ("an extra key", {"steps": [DRIVE], "run": True}, "run", "unknown key run (allowed: format, steps)"),
    ("a step not an object", {"steps": [3]}, "steps[0]", "a step is a JSON object with a kind; got 3."),
    ("a step without a kind", {"steps": [{"skill": "go_to_goal"}]}, "steps[0].kind", "kind must be one of skill"),
    ("an unknown kind", step(kind="exec", code="rm"), "steps[0].kind", "got 'exec'."),
    ("an extra key in a step", step(**DRIVE, exec="x"), "steps[0].exec", "unknown key exec"),
    ("a strange key", step(**DRIVE, **{"\u202e\x00": 1}), "steps[0].'\\u202e\\x00'", "unknown key"),
    ("a missing key", step(kind="drive", linear_mps=0.1, duration_s=1), "steps[0].angular_radps",
     "a drive step needs angular_radps"),
    ("a bool for a number", step(**{**DRIVE, "linear_mps": True}), "steps[0].linear_mps",
     "linear_mps must be a number; got true."),
    ("a string for a number", step(**{**DRIVE, "duration_s": "2s"}), "steps[0].duration_s", "must be a number"),
    ("a huge int", step(**{**DRIVE, "linear_mps": 10**400}), "steps[0].linear_mps", "must be a finite number"),
    ("a huge count", step(kind="repeat", count=10**400, body=[DRIVE]), "steps[0].count", "must be a finite number"),
    ("a count too large", step(kind="repeat", count=10**9, body=[DRIVE]), "steps[0].count", "got 1000000000."),
    ("a fractional count", step(kind="repeat", count=2.5, body=[DRIVE]), "steps[0].count", "whole number"),
    ("NaN", step(**{**DRIVE, "angular_radps": math.nan}), "steps[0].angular_radps", "must be a finite number"),
    ("infinity", step(**{**DRIVE, "duration_s": math.inf}), "steps[0].duration_s", "must be a finite number"),
    ("a zero duration", step(**{**DRIVE, "duration_s": 0}), "steps[0].duration_s", "more than 0 s"),
    ("an unknown skill", step(kind="skill", skill="self_destruct"), "steps[0].skill",
     "no skill 'self_destruct' that a plan can run"),
    ("a skill name with control characters", step(kind="skill", skill="go\x00to"), "steps[0].skill",
     "no skill 'go\\x00to'"),
    ("parameters not an object", step(kind="skill", skill="go_to_goal", parameters=[1, 2]), "steps[0].parameters",
     "parameters must be an object"),
    ("too many parameters", step(kind="skill", skill="go_to_goal", parameters={f"p{i}": 1 for i in range(33)}),
     "steps[0].parameters", "at most 32 values"),
    ("an unknown parameter", step(kind="skill", skill="go_to_goal", parameters={"warp": 9}),
     "steps[0].parameters.warp", "go_to_goal has no parameter 'warp'"),
    ("a parameter out of range", step(kind="skill", skill="go_to_goal", parameters={"goal_x_m": 1e9}),
     "steps[0].parameters.goal_x_m", "goal_x_m must be between -50 and 50 m; got 1e+09."),
    ("a nested parameter", step(kind="skill", skill="go_to_goal", parameters={"goal_x_m": {"$gt": 1}}),
     "steps[0].parameters.goal_x_m", "goal_x_m must be a number; got an object."),
    ("a wrong enum", step(kind="skill", skill="wall_following", parameters={"side": "up"}),
     "steps[0].parameters.side", "side must be one of left, right; got 'up'."),
    ("a bool for an int", step(kind="skill", skill="localization", parameters={"particle_count": True}),
     "steps[0].parameters.particle_count", "must be a number"),
    ("a negative line", step(**DRIVE, line=-1), "steps[0].line", "line must be a whole number from 0"),
    ("a bool column", step(**DRIVE, column=True), "steps[0].column", "got true"),
    ("a say with a NUL", step(kind="say", text="a\x00b"), "steps[0].text", "U+0000 is not allowed"),
    ("a say with a line break", step(kind="say", text="a\nb"), "steps[0].text", "U+000A is not allowed"),
    ("a say too long", step(kind="say", text="x" * 201), "steps[0].text", "at most 200 characters"),
    ("a say not a string", step(kind="say", text=["x"]), "steps[0].text", "say needs some text"),
    ("a wait without anything", step(kind="wait"), "steps[0].duration_s", "a wait needs a duration_s, a condition"),
    ("a condition not an object", step(kind="wait", condition="goal_reached"), "steps[0].condition",
     "condition must be an object"),
    ("a condition without a kind", step(kind="wait", condition={"value": 1}), "steps[0].condition.kind",
     "kind must be one of obstacle_within"),
    ("an unknown condition", step(kind="wait", condition={"kind": "door_open"}), "steps[0].condition.kind",
     "'door_open' is not a condition"),
    ("goal_reached with a value", step(kind="wait", condition={"kind": "goal_reached", "value": 1}),
     "steps[0].condition.value", "goal_reached takes no value"),
    ("negate not a bool", step(kind="wait", condition={"kind": "goal_reached", "negate": 1}),
     "steps[0].condition.negate", "negate must be true or false"),
    ("an extra condition key", step(kind="wait", condition={"kind": "goal_reached", "x": 1}),
     "steps[0].condition.x", "unknown key x"),
    ("an unknown setting", step(kind="set", setting="turbo", value=1), "steps[0].setting", "'turbo' is not a setting"),
    ("a setting not a string", step(kind="set", setting=None, value=1), "steps[0].setting", "got nothing"),
    ("body not a list", step(kind="repeat", count=2, body=DRIVE), "steps[0].body", "must be a list of steps"),
    ("an empty body", step(kind="repeat", count=2, body=[]), "steps[0].body", "nothing in its body"),
    ("an if without then", step(kind="if", condition={"kind": "goal_reached"}), "steps[0].then",
     "an if step needs then"),
    ("an empty plan", {"steps": []}, "steps", "the plan is empty"),
]


@pytest.mark.parametrize(("name", "doc", "field", "message"), HOSTILE_JSON, ids=[h[0] for h in HOSTILE_JSON])
def test_a_hostile_json_plan_is_refused_naming_the_json_path(skills: SkillSchemas, name: str, doc: object,
                                                             field: str, message: str) -> None:
    with pytest.raises(PlanInvalid) as refused:
        plan_from_json(doc, skills)
    first = refused.value.errors[0]
    assert first.field == field, first
    assert message in first.message, first.message
    json.dumps(refused.value.to_dict())  # the error itself is JSON


def deep_json(depth: int) -> dict[str, object]:
    """repeat steps depth deep around a say."""
    inner: dict[str, object] = {"kind": "say", "text": "deep"}
    for _ in range(depth):
        inner = {"kind": "repeat", "count": 2, "body": [inner]}
    return {"steps": [inner]}


def test_json_nesting_stops_at_eight_blocks(skills: SkillSchemas) -> None:
    assert plan_from_json(deep_json(8), skills)
    with pytest.raises(PlanInvalid) as refused:
        plan_from_json(deep_json(9), skills)
    assert refused.value.field == "steps[0]" + ".body[0]" * 8 + ".body"
    with pytest.raises(PlanInvalid):
        plan_from_json(deep_json(900), skills)  # read no deeper than the limit, whatever the depth


def test_json_steps_stop_at_500_and_errors_at_50(skills: SkillSchemas) -> None:
    with pytest.raises(PlanInvalid) as refused:
        plan_from_json({"steps": [DRIVE] * 1_000_000}, skills)
    assert [e.field for e in refused.value.errors] == ["steps[500]"]
    assert "at most 500 steps" in refused.value.message
    with pytest.raises(PlanInvalid) as refused:
        plan_from_json({"steps": [{"kind": "say"}] * 400}, skills)
    assert len(refused.value.errors) == 50
    assert refused.value.errors[-1].field == "steps[49].text"


def test_json_errors_carry_the_steps_line_and_column(skills: SkillSchemas) -> None:
    doc = {"steps": [{**DRIVE, "line": 1, "column": 1},
                     {"kind": "repeat", "count": 3, "line": 2, "column": 1,
                      "body": [{"kind": "say", "text": "", "line": 3, "column": 5}]}]}
    with pytest.raises(PlanInvalid) as refused:
        plan_from_json(doc, skills)
    assert [(e.line, e.column, e.field) for e in refused.value.errors] == [(3, 5, "steps[1].body[0].text")]
    assert refused.value.message.startswith("line 3, column 5: say needs some text")
    with pytest.raises(PlanInvalid) as refused:
        plan_from_json({"steps": [{"kind": "say", "text": ""}]}, skills)
    assert refused.value.message.startswith("steps[0].text: say needs some text")
