"""A checked plan as the RunPlan request's PlanBlock: every step kind, its line and column, typed parameter values."""

from __future__ import annotations

from middleware.plans import parse_plan_text
from middleware.plans.proto_form import plan_to_proto
from middleware.teaching.command_form import SkillSchemas
from protos.telelab.v1 import robot_pb2

TEXT = """go_to 1.2 0.5 speed=0.3
localization particle_count=500 initial_x_m=1
follow_wall left 0.4 for 20s
drive 0.2 -0.5 for 2s
wait_until not obstacle_within 0.5 timeout 10s
wait 1s
repeat 3 {
  say "lap"
}
if goal_reached {
  set max_speed 0.3
} else {
  set watchdog 0.5s
}
"""


def test_every_step_kind_becomes_its_proto_with_its_line_and_column(skills: SkillSchemas) -> None:
    block = plan_to_proto(parse_plan_text(TEXT, skills))
    assert isinstance(block, robot_pb2.PlanBlock)
    steps = block.steps
    assert [s.WhichOneof("kind") for s in steps] == ["skill", "skill", "skill", "drive", "wait", "wait", "repeat",
                                                    "branch"]
    assert [(s.line, s.column) for s in steps] == [(1, 1), (2, 1), (3, 1), (4, 1), (5, 1), (6, 1), (7, 1), (10, 1)]
    go_to = steps[0].skill
    assert go_to.skill == "go_to_goal" and go_to.duration_s == 0
    assert {k: v.WhichOneof("kind") for k, v in go_to.parameters.items()} == {
        "goal_x_m": "double_value", "goal_y_m": "double_value", "speed_mps": "double_value"}
    assert go_to.parameters["goal_x_m"].double_value == 1.2
    localization = steps[1].skill.parameters
    assert localization["particle_count"].WhichOneof("kind") == "int_value"
    assert localization["particle_count"].int_value == 500
    assert localization["initial_x_m"].WhichOneof("kind") == "double_value"
    modelling = plan_to_proto(parse_plan_text("environment_modelling restart=true", skills)).steps[0].skill
    assert modelling.parameters["restart"].WhichOneof("kind") == "bool_value"
    assert modelling.parameters["restart"].bool_value
    wall = steps[2].skill
    assert wall.parameters["side"].string_value == "left" and wall.duration_s == 20.0
    assert (steps[3].drive.linear_mps, steps[3].drive.angular_radps, steps[3].drive.duration_s) == (0.2, -0.5, 2.0)
    wait = steps[4].wait
    assert wait.HasField("condition") and wait.duration_s == 10.0
    assert (wait.condition.kind, wait.condition.value, wait.condition.negate) == ("obstacle_within", 0.5, True)
    assert not steps[5].wait.HasField("condition") and steps[5].wait.duration_s == 1.0
    repeat = steps[6].repeat
    assert repeat.count == 3 and repeat.body.steps[0].say.text == "lap"
    assert (repeat.body.steps[0].line, repeat.body.steps[0].column) == (8, 3)
    branch = steps[7].branch
    assert branch.condition.kind == "goal_reached" and branch.condition.value == 0
    assert branch.then_block.steps[0].set.setting == "max_speed"
    assert branch.else_block.steps[0].set.value == 0.5
    assert (branch.else_block.steps[0].line, branch.else_block.steps[0].column) == (13, 3)


def test_the_proto_survives_the_wire(skills: SkillSchemas) -> None:
    block = plan_to_proto(parse_plan_text(TEXT, skills))
    request = robot_pb2.RunPlanRequest(token="t", name="patrol", plan=block)
    assert robot_pb2.RunPlanRequest.FromString(request.SerializeToString()).plan == block
