"""The language and the skill server agree: any plan the language accepts (motor skills only, as a plan runs them)
passes the skill server's own checks once it has travelled as a RunPlan request, with its lines and columns."""

from __future__ import annotations

from hypothesis import given

from middleware.plans import Plan, PlanInvalid, parse_plan_text, plan_from_json, plan_to_json
from middleware.plans.proto_form import plan_to_proto
from protos.telelab.v1 import robot_pb2
from skill_server.plans.validation import check_plan
from skill_server.service.plan_convert import plan_from_proto
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.catalog import default_registry
from tests.unit.plans.catalogue import motor_schemas
from tests.unit.plans.test_plan_properties import PROPERTY_SETTINGS, plans_of

MOTOR_SKILLS = motor_schemas()
SPEC = RobotSpec()
REGISTRY = default_registry(SPEC)


def on_the_skill_server(plan: Plan) -> object:
    """The skill server's checked plan for this plan, as it arrives in a RunPlan request."""
    request = robot_pb2.RunPlanRequest(token="t", name="checked", plan=plan_to_proto(plan))
    wire = robot_pb2.RunPlanRequest.FromString(request.SerializeToString())
    return check_plan(plan_from_proto(wire), REGISTRY, SPEC)


@PROPERTY_SETTINGS
@given(plans_of(MOTOR_SKILLS))
def test_a_plan_the_language_accepts_the_skill_server_accepts(plan: Plan) -> None:
    try:
        checked = plan_from_json(plan_to_json(plan), MOTOR_SKILLS)
    except PlanInvalid:
        return
    on_the_skill_server(checked)


def test_the_skill_server_sees_the_lines_and_the_expanded_count_the_language_gives() -> None:
    plan = parse_plan_text("go_to 1 0.5 speed=0.2\nrepeat 3 {\n  follow_wall left 0.4 for 5s\n  if goal_reached {\n"
                           "    say \"ok\"\n  } else {\n    drive 0.1 0 for 1s\n  }\n}\nturn_to 90deg\n", MOTOR_SKILLS)
    checked = on_the_skill_server(plan)
    assert checked.expanded_steps == 1 + 3 * (1 + 1 + 1 + 1) + 1  # type: ignore[attr-defined]
    lines = checked.plan.steps  # type: ignore[attr-defined]
    assert [(line.line, line.column) for line in lines] == [(1, 1), (2, 1), (10, 1)]
    assert [(line.line, line.column) for line in lines[1].body] == [(3, 3), (4, 3)]
