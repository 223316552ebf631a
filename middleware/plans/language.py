"""The plan language: a plan read from its text or JSON form, checked, and written back in either form.

Pure: no Flask request, no gRPC. Nothing a user writes is ever run as code: the text is read by a hand-written
tokenizer and recursive-descent parser (middleware.plans.text_form), the JSON by a validator
(middleware.plans.json_form); both check every parameter against the robot's skill schemas and every limit in
middleware.plans.steps, and report all the problems they find as PlanError(line, column, field, message).
"""

from __future__ import annotations

from middleware.plans.aliases import ALIASES, Alias
from middleware.plans.json_form import plan_from_json, plan_to_json
from middleware.plans.steps import (
    EVENTS,
    FORMAT,
    MAX_DEPTH,
    MAX_EXPANDED_STEPS,
    MAX_LINES,
    MAX_PLAN_DURATION_S,
    MAX_REPEAT,
    MAX_SAY_CHARS,
    MAX_STEP_DURATION_S,
    MAX_TEXT_BYTES,
    Condition,
    DriveStep,
    IfStep,
    OnStep,
    Plan,
    PlanError,
    PlanInvalid,
    RepeatStep,
    SayStep,
    SetStep,
    SkillStep,
    Step,
    WaitStep,
    is_plan_name,
)
from middleware.plans.summary import plan_summary
from middleware.plans.text_form import parse_plan_text
from middleware.plans.text_writer import plan_to_text
from middleware.teaching.command_form import SkillSchemas

__all__ = [
    "ALIASES", "EVENTS", "Alias", "FORMAT", "MAX_DEPTH", "MAX_EXPANDED_STEPS", "MAX_LINES", "MAX_PLAN_DURATION_S",
    "MAX_REPEAT", "MAX_SAY_CHARS", "MAX_STEP_DURATION_S", "MAX_TEXT_BYTES", "Condition", "DriveStep", "IfStep",
    "OnStep", "Plan", "PlanError", "PlanInvalid", "RepeatStep", "SayStep", "SetStep", "SkillSchemas", "SkillStep",
    "Step", "WaitStep", "is_plan_name", "parse_plan_text", "plan_from_json", "plan_summary", "plan_to_json",
    "plan_to_text",
]
