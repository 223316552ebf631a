"""line_seen, the line sensor's condition: read, checked, written back and sent as the robot takes it; its text is
also among the plans the Blockly round trip converts (tests/unit/plans/test_plan_blocks_roundtrip.py)."""

from __future__ import annotations

import pytest

from middleware.plans import Condition, IfStep, PlanInvalid, WaitStep, parse_plan_text, plan_to_text
from middleware.teaching.command_form import SkillSchemas

LINE_PLAN = """wait_until line_seen timeout 10s
repeat 3 {
  if not line_seen {
    drive 0 0.5 for 1s
  } else {
    drive 0.2 0 for 1s
  }
}
"""


def test_line_seen_is_a_condition_without_a_value_and_reads_back(skills: SkillSchemas) -> None:
    plan = parse_plan_text(LINE_PLAN, skills)
    wait, repeat = plan.steps
    assert isinstance(wait, WaitStep) and wait.condition == Condition("line_seen", None, False)
    branch = repeat.body[0]
    assert isinstance(branch, IfStep) and branch.condition == Condition("line_seen", None, True)
    assert plan_to_text(plan) == LINE_PLAN


def test_line_seen_with_a_value_is_refused_naming_it(skills: SkillSchemas) -> None:
    with pytest.raises(PlanInvalid) as refused:
        parse_plan_text("wait_until line_seen 0.5\n", skills)
    assert "line_seen takes no value" in str(refused.value)
