"""What a plan amounts to: its steps multiplied out, a bound on its duration, the skills it uses."""

from __future__ import annotations

from collections.abc import Iterable, Iterator

from middleware.plans.steps import DriveStep, IfStep, OnStep, Plan, RepeatStep, SkillStep, Step, WaitStep


def expanded_count(steps: Iterable[Step]) -> int:
    """Steps as the skill server counts them: a repeat's body count times; an if, and both its branches."""
    total = 0
    for step in steps:
        if isinstance(step, RepeatStep):
            total += step.count * expanded_count(step.body)
        elif isinstance(step, IfStep):
            total += 1 + expanded_count(step.then) + expanded_count(step.otherwise)  # the test is a step too
        elif isinstance(step, OnStep):
            total += 1 + expanded_count(step.body)  # its body, once: it runs in the place of a line cut short
        else:
            total += 1
    return total


def duration_bound_s(steps: Iterable[Step]) -> float | None:
    """The longest the steps can take, or None when a step has no bound (a skill or a wait with no time limit).
    After an on, a line cut short runs the on's body in its place: the bound adds the longest body to each line."""
    total = 0.0
    handler_s = 0.0  # the longest body of the ons in force
    for step in steps:
        part: float | None
        if isinstance(step, OnStep):
            body = duration_bound_s(step.body)
            if body is None:
                return None
            handler_s = max(handler_s, body)
            continue
        if isinstance(step, RepeatStep):
            body = duration_bound_s(step.body)
            part = None if body is None else step.count * body
        elif isinstance(step, IfStep):
            then, otherwise = duration_bound_s(step.then), duration_bound_s(step.otherwise)
            part = None if then is None or otherwise is None else max(then, otherwise)
        elif isinstance(step, SkillStep):
            timeout = dict(step.parameters).get("timeout_s")
            part = step.duration_s if step.duration_s is not None else (
                float(timeout) if isinstance(timeout, int | float) and not isinstance(timeout, bool) else None)
        elif isinstance(step, DriveStep | WaitStep):
            part = step.duration_s
        else:
            part = 0.0
        if part is None:
            return None
        total += part + (handler_s * expanded_count((step,)) if handler_s else 0.0)
    return total


def certain_duration_s(steps: Iterable[Step]) -> float:
    """The time the steps take at the least: drives and plain waits (a skill or a condition may end early, and an
    on may cut any line after it short)."""
    total = 0.0
    for step in steps:
        if isinstance(step, OnStep):
            break
        if isinstance(step, RepeatStep):
            total += step.count * certain_duration_s(step.body)
        elif isinstance(step, IfStep):
            total += min(certain_duration_s(step.then), certain_duration_s(step.otherwise))
        elif isinstance(step, DriveStep):
            total += step.duration_s
        elif isinstance(step, WaitStep) and step.condition is None:
            total += step.duration_s or 0.0
    return total


def walk(steps: Iterable[Step]) -> Iterator[Step]:
    """Every step as written, blocks' insides after their heads."""
    for step in steps:
        yield step
        if isinstance(step, RepeatStep):
            yield from walk(step.body)
        elif isinstance(step, IfStep):
            yield from walk(step.then)
            yield from walk(step.otherwise)
        elif isinstance(step, OnStep):
            yield from walk(step.body)


def plan_summary(plan: Plan) -> dict[str, object]:
    """{"steps": steps multiplied out, "max_duration_s": a bound or None, "skills": the skills it uses, sorted}."""
    bound = duration_bound_s(plan.steps)
    return {
        "steps": expanded_count(plan.steps),
        "max_duration_s": None if bound is None else round(bound, 6),  # 20.56, not 20.560000000000002
        "skills": sorted({step.skill for step in walk(plan.steps) if isinstance(step, SkillStep)}),
    }
