"""Plans: sequences of skills, timed drives, waits, repeat/if blocks, on blocks that react to events, settings and
messages that students write, check, store and run on a robot as one goal (issue 16). The language (text and JSON
forms, checks, limits) is in middleware.plans.language; import the names below from here or from there."""

from __future__ import annotations

from middleware.plans.language import (
    FORMAT,
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
    SkillSchemas,
    SkillStep,
    Step,
    WaitStep,
    is_plan_name,
    parse_plan_text,
    plan_from_json,
    plan_summary,
    plan_to_json,
    plan_to_text,
)

__all__ = [
    "FORMAT", "Condition", "DriveStep", "IfStep", "OnStep", "Plan", "PlanError", "PlanInvalid", "RepeatStep", "SayStep",
    "SetStep", "SkillSchemas", "SkillStep", "Step", "WaitStep", "is_plan_name", "parse_plan_text", "plan_from_json",
    "plan_summary", "plan_to_json", "plan_to_text",
]
