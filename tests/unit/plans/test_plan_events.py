"""`on <event> { }` in the plan language (issue 33): read, written back, carried as JSON and as the RunPlan proto,
accepted by the skill server's own checks, and refused with a sentence naming the line, the column and the field."""

from __future__ import annotations

import pytest

from middleware.plans import DriveStep, Plan, PlanInvalid, SayStep, parse_plan_text, plan_from_json, plan_to_json
from middleware.plans.language import OnStep, plan_summary, plan_to_text
from middleware.plans.proto_form import plan_to_proto
from middleware.teaching.command_form import SkillSchemas
from protos.telelab.v1 import robot_pb2
from skill_server.plans.validation import check_plan
from skill_server.service.plan_convert import plan_from_proto
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.catalog import default_registry

REACTING = """# Drives ahead, backing off and turning whenever something comes within 40 cm.
on obstacle_detected 0.4 {
  say "Something ahead: turning"
  drive -0.1 0 for 1s
  drive 0 0.8 for 2s
}
repeat 5 {
  drive 0.2 0 for 2s
}
on goal_reached {
  say "arrived"
}
go_to 1.2 0.5
"""


def test_an_on_block_is_read_with_its_event_value_and_body_and_written_back_identically(skills: SkillSchemas) -> None:
    plan = parse_plan_text(REACTING, skills)
    first = plan.steps[0]
    assert isinstance(first, OnStep)
    assert (first.event, first.value, first.line, first.column) == ("obstacle_detected", 0.4, 2, 1)
    assert first.body == (SayStep("Something ahead: turning"), DriveStep(-0.1, 0.0, 1.0), DriveStep(0.0, 0.8, 2.0))
    third = plan.steps[2]
    assert isinstance(third, OnStep) and (third.event, third.value) == ("goal_reached", None)
    assert plan_to_text(plan) == REACTING.split("\n", 1)[1]  # the comment aside, the same text
    assert plan_from_json(plan_to_json(plan), skills) == plan
    on_json = plan_to_json(plan)["steps"][0]  # type: ignore[index]
    assert on_json["kind"] == "on" and on_json["event"] == "obstacle_detected" and on_json["value"] == 0.4


def test_the_skill_server_accepts_the_on_blocks_the_language_accepts(skills: SkillSchemas) -> None:
    plan = parse_plan_text(REACTING, skills)
    request = robot_pb2.RunPlanRequest(token="t", name="reacting", plan=plan_to_proto(plan))
    wire = robot_pb2.RunPlanRequest.FromString(request.SerializeToString())
    checked = check_plan(plan_from_proto(wire), default_registry(RobotSpec()), RobotSpec())
    on = checked.plan.steps[0]
    assert (on.line, on.event, on.value, len(on.body)) == (2, "obstacle_detected", 0.4, 3)  # type: ignore[union-attr]
    assert wire.plan.steps[2].on.value == 0.0  # no value: the event's default
    assert checked.expanded_steps == plan_summary(plan)["steps"]


def test_the_summary_counts_a_body_once_and_bounds_each_line_it_may_replace(skills: SkillSchemas) -> None:
    plan = parse_plan_text("on obstacle_detected {\n  drive 0 1 for 2s\n}\nrepeat 3 {\n  drive 0.1 0 for 1s\n}\n",
                           skills)
    summary = plan_summary(plan)
    assert summary["steps"] == 1 + 1 + 3
    assert summary["max_duration_s"] == 3 * (1 + 2)  # each drive may be cut short and followed by the body


@pytest.mark.parametrize(("text", "line", "column", "field", "message"), [
    ("on obstacle_spotted {\n  say \"x\"\n}\nwait 1s", 1, 4, "steps[0].event",
     "line 1, column 4: 'obstacle_spotted' is not an event (did you mean obstacle_detected?)"),
    ("on {\n  say \"x\"\n}\nwait 1s", 1, 1, "steps[0].event", "line 1, column 1: on needs an event"),
    ("on wall_lost 0.3 {\n  say \"x\"\n}\nwait 1s", 1, 14, "steps[0].value",
     "line 1, column 14: wall_lost takes no value; got 0.3."),
    ("on obstacle_detected 5m {\n  say \"x\"\n}\nwait 1s", 1, 22, "steps[0].value",
     "line 1, column 22: obstacle_detected must be between 0.05 and 3 m; got 5m."),
    ("on obstacle_detected 20deg {\n  say \"x\"\n}\nwait 1s", 1, 22, "steps[0].value",
     "line 1, column 22: obstacle_detected is a distance in m; 20deg is an angle"),
    ("on battery_low 0.2 0.3 {\n  say \"x\"\n}\nwait 1s", 1, 20, "steps[0].value",
     "line 1, column 20: battery_low takes at most one value."),
    ("on goal_reached\nwait 1s", 1, 1, "steps[0].body", "line 1, column 1: on needs a block"),
    ("wait 1s\non goal_reached {\n  say \"x\"\n}", 2, 1, "steps[1]",
     "line 2, column 1: this on handles nothing: it watches the lines after it in its block, and none follows."),
    ("on goal_reached {\n  on wall_lost {\n    say \"x\"\n  }\n  say \"y\"\n}\nwait 1s", 2, 3, "steps[0].body[0]",
     "line 2, column 3: an on block cannot hold another on"),
    ("on localized {\n  say \"x\"\n}\non localized {\n  say \"y\"\n}\nwait 1s", 4, 1, "steps[1].event",
     "line 4, column 1: localized is handled already on line 1 of this block"),
    ("on localized {\n}\nwait 1s", 1, 1, "steps[0].body", "line 1, column 1: this on has nothing in its block."),
])
def test_an_on_that_cannot_work_is_refused_naming_its_line_column_and_field(
        skills: SkillSchemas, text: str, line: int, column: int, field: str, message: str) -> None:
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text(text, skills)
    first = refused.value.errors[0]
    assert (first.line, first.column, first.field) == (line, column, field), first
    assert first.message.startswith(message), first.message


def test_the_json_form_refuses_the_same_on_naming_its_path(skills: SkillSchemas) -> None:
    doc = {"format": "telelab-plan/1", "steps": [
        {"kind": "on", "event": "wall_lost", "value": 1, "body": [{"kind": "say", "text": "x"}], "line": 3},
        {"kind": "say", "text": "y"}]}
    with pytest.raises(PlanInvalid) as refused:
        plan_from_json(doc, skills)
    first = refused.value.errors[0]
    assert (first.line, first.field) == (3, "steps[0].value") and "wall_lost takes no value" in first.message
    assert isinstance(plan_from_json({**doc, "steps": [{**doc["steps"][0], "value": None}, doc["steps"][1]]},  # type: ignore[index, dict-item]
                                     skills), Plan)
