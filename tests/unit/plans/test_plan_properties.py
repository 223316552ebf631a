"""Property tests: any plan the language accepts reads back unchanged from its JSON and from its text, and no text
or JSON, however strange, raises anything but PlanInvalid."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from middleware.plans import (
    Condition,
    DriveStep,
    IfStep,
    OnStep,
    Plan,
    PlanInvalid,
    RepeatStep,
    SayStep,
    SetStep,
    SkillStep,
    Step,
    WaitStep,
    parse_plan_text,
    plan_from_json,
    plan_to_json,
    plan_to_text,
)
from middleware.teaching.command_form import SkillSchemas
from tests.unit.plans.catalogue import catalogue_schemas

SKILLS = catalogue_schemas()
PROPERTY_SETTINGS = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def value_of(schema: Mapping[str, object]) -> st.SearchStrategy[object]:
    """Values one parameter schema accepts."""
    kind = schema["type"]
    if kind == "bool":
        return st.booleans()
    if kind == "enum":
        choices = schema["choices"]
        assert isinstance(choices, list)
        return st.sampled_from(choices)
    low, high = float(schema["minimum"]), float(schema["maximum"])  # type: ignore[arg-type]
    if kind == "int":
        return st.integers(math.ceil(low), math.floor(high))
    return st.floats(low, high, allow_nan=False, allow_infinity=False)


@st.composite
def skill_steps(draw: st.DrawFn, skills: SkillSchemas) -> Step:
    name = draw(st.sampled_from(sorted(skills)))
    schemas: Sequence[Mapping[str, object]] = skills[name]
    chosen = draw(st.lists(st.sampled_from(schemas), unique_by=lambda s: s["name"], max_size=len(schemas))) \
        if schemas else []
    parameters = tuple((str(s["name"]), draw(value_of(s))) for s in chosen)
    duration = draw(st.none() | durations)
    return SkillStep(name, parameters, duration)


durations = st.floats(0.001, 600.0, allow_nan=False).filter(lambda d: d > 0)
conditions = st.one_of(
    st.builds(Condition, st.just("goal_reached"), st.none(), st.booleans()),
    st.builds(Condition, st.just("obstacle_within"), st.floats(0.05, 8.0), st.booleans()),
    st.builds(Condition, st.just("battery_below"), st.floats(0.01, 1.0), st.booleans()),
)
say_texts = st.text(st.characters(blacklist_categories=("Cc", "Cs", "Zl", "Zp", "Cf")), min_size=1, max_size=200) \
    .filter(lambda t: t.strip() != "")


def simple_steps(skills: SkillSchemas) -> st.SearchStrategy[Step]:
    """Every step kind but the blocks, with values the language accepts."""
    return st.one_of(
        skill_steps(skills),
        st.builds(DriveStep, st.floats(-0.5, 0.5), st.floats(-1.5, 1.5), st.floats(0.001, 5.0)),
        st.builds(WaitStep, st.none(), st.floats(0.001, 5.0)),
        st.builds(WaitStep, conditions, st.none() | st.floats(0.001, 600.0)),
        st.builds(SetStep, st.just("max_speed"), st.floats(0.05, 0.5)),
        st.builds(SetStep, st.just("max_turn_rate"), st.floats(0.1, 1.5)),
        st.builds(SetStep, st.just("watchdog"), st.floats(0.2, 5.0)),
        st.builds(SayStep, say_texts),
    )


events = st.one_of(
    st.tuples(st.sampled_from(["wall_lost", "goal_reached", "localized"]), st.none()),
    st.tuples(st.just("obstacle_detected"), st.none() | st.floats(0.05, 3.0)),
    st.tuples(st.just("battery_low"), st.none() | st.floats(0.01, 1.0)),
)


def blocks(children: st.SearchStrategy[Step]) -> st.SearchStrategy[Step]:
    """repeat, if and on around smaller steps."""
    body = st.lists(children, min_size=1, max_size=4).map(tuple)
    return st.one_of(
        st.builds(RepeatStep, st.integers(1, 3), body),
        st.builds(IfStep, conditions, st.lists(children, max_size=3).map(tuple),
                  st.lists(children, max_size=3).map(tuple)),
        st.builds(lambda event, body: OnStep(event[0], event[1], body), events, body),
    )


def plans_of(skills: SkillSchemas) -> st.SearchStrategy[Plan]:
    """Plans of up to 8 steps and 20 leaves using the given skills."""
    return st.lists(st.recursive(simple_steps(skills), blocks, max_leaves=20), min_size=1, max_size=8) \
        .map(lambda steps: Plan(tuple(steps)))


plans = plans_of(SKILLS)


def accepted(plan: Plan) -> Plan | None:
    """The plan as the language reads it from its JSON form, or None when it breaks a plan-wide limit."""
    try:
        return plan_from_json(plan_to_json(plan), SKILLS)
    except PlanInvalid:
        return None


@PROPERTY_SETTINGS
@given(plans)
def test_an_accepted_plan_reads_back_unchanged_from_its_json_and_its_text(plan: Plan) -> None:
    checked = accepted(plan)
    if checked is None:
        return
    assert checked == plan
    document = json.loads(json.dumps(plan_to_json(checked), allow_nan=False))
    assert plan_to_json(plan_from_json(document, SKILLS)) == plan_to_json(checked)
    text = plan_to_text(checked)
    again = parse_plan_text(text, SKILLS)
    assert again == checked
    assert plan_to_text(again) == text
    assert plan_from_json(plan_to_json(again), SKILLS) == checked


WORDS = ["go_to", "turn_to", "follow_wall", "drive", "wait", "wait_until", "repeat", "if", "else", "set", "say",
         "for", "timeout", "not", "goal_reached", "obstacle_within", "battery_below", "max_speed", "watchdog",
         "left", "right", "true", "false", "speed", "go_to_goal", "goal_x_m", "goal_y_m", "wall_following",
         "nan", "inf"]
PIECES = st.one_of(
    st.sampled_from(WORDS), st.sampled_from(["{", "}", "=", "\n", "\n", "#", '"', " ", "\t", "\r\n", "\ufeff"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10**6, 10**6).map(str),
    st.tuples(st.floats(-5, 5), st.sampled_from(["", "m", "cm", "s", "ms", "deg", "rad", "m/s", "x"]))
    .map(lambda t: f"{t[0]:g}{t[1]}"),
    st.text(max_size=12).map(lambda t: '"' + t + '"'),
    st.text(max_size=4),
)


@PROPERTY_SETTINGS
@given(st.lists(PIECES, max_size=60).map(" ".join))
def test_any_text_is_a_plan_or_a_plan_invalid_and_an_accepted_one_round_trips(text: str) -> None:
    try:
        plan = parse_plan_text(text, SKILLS)
    except PlanInvalid as refused:
        assert refused.errors and all(e.message for e in refused.errors)
        assert all(e.line >= 0 and e.column >= 0 for e in refused.errors)
        return
    assert parse_plan_text(plan_to_text(plan), SKILLS) == plan
    assert plan_from_json(plan_to_json(plan), SKILLS) == plan


EDIT_CHARACTERS = st.sampled_from(list("0123456789.-+ \t\n{}=\"#\\edgmsx_") + ["cm", "deg", "m/s", "not ", "é", "\x00"])


@st.composite
def edited_texts(draw: st.DrawFn) -> str:
    """The text of an accepted plan with a few characters deleted, inserted or replaced: mostly nearly right."""
    checked = accepted(draw(plans))
    text = plan_to_text(checked) if checked else 'say "x"\n'
    for _ in range(draw(st.integers(1, 3))):
        at = draw(st.integers(0, len(text)))
        cut = draw(st.integers(0, 2))
        text = text[:at] + draw(st.sampled_from(["", draw(EDIT_CHARACTERS)])) + text[at + cut:]
    return text


@PROPERTY_SETTINGS
@given(edited_texts())
def test_a_nearly_right_text_is_a_plan_or_a_plan_invalid_and_an_accepted_one_round_trips(text: str) -> None:
    try:
        plan = parse_plan_text(text, SKILLS)
    except PlanInvalid as refused:
        assert refused.errors and all(e.message.startswith(("line ", "steps", "text")) for e in refused.errors)
        return
    written = plan_to_text(plan)
    assert parse_plan_text(written, SKILLS) == plan
    assert plan_to_text(parse_plan_text(written, SKILLS)) == written
    assert plan_from_json(plan_to_json(plan), SKILLS) == plan


def _json_containers(children: st.SearchStrategy) -> st.SearchStrategy:
    # A def: Hypothesis reads a lambda's source to see that it recurses, and misreads one split over lines.
    return st.lists(children, max_size=4) | st.dictionaries(
        st.sampled_from(["kind", "steps", "skill", "parameters", "count", "body", "text", "condition", "value",
                         "duration_s", "linear_mps", "angular_radps", "then", "else", "setting", "line", "format"]),
        children, max_size=5)


json_values = st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
                           _json_containers, max_leaves=25)


@PROPERTY_SETTINGS
@given(json_values)
def test_any_json_is_a_plan_or_a_plan_invalid(doc: object) -> None:
    try:
        plan = plan_from_json(doc, SKILLS)
    except PlanInvalid as refused:
        assert refused.errors
        json.dumps(refused.to_dict())
        return
    assert plan_from_json(plan_to_json(plan), SKILLS) == plan
