"""The prediction's parts that need no robot: the trace thinned to a point a centimetre, the slots (one per user, at
most the cap at once), and the lines of a plan's `set watchdog` a course may keep from its students."""

from __future__ import annotations

import math
import time

import pytest

from middleware.errors import ApiError
from middleware.farm.base import FarmUnavailable, RobotSpec
from middleware.plans.language import parse_plan_text
from middleware.plans.predictions import (
    MAX_TRACE_POINTS,
    PredictionRequest,
    PredictionSlots,
    add_trace_point,
    run_prediction,
)
from middleware.plans.runs import check_settings_permitted, watchdog_lines
from middleware.teaching.command_form import SkillSchemas


def test_the_trace_keeps_a_point_a_centimetre_and_its_end_follows_the_robot() -> None:
    points: list[dict[str, float]] = []
    for i in range(501):  # 1 m at 2 mm a sample
        add_trace_point(points, i * 0.002, 0.0, 0.0)
    assert 80 <= len(points) <= 101, len(points)
    gaps = [math.hypot(b["x_m"] - a["x_m"], b["y_m"] - a["y_m"]) for a, b in zip(points, points[1:], strict=False)]
    assert all(gap >= 0.0099 for gap in gaps[:-1]) and max(gaps) < 0.0125, gaps
    assert points[-1]["x_m"] == pytest.approx(1.0)
    resting = len(points)
    for _ in range(50):  # standing still: nothing is added
        add_trace_point(points, 1.0, 0.0001, 0.0)
    assert len(points) == resting
    add_trace_point(points, math.nan, 0.0, 0.0)
    add_trace_point(points, math.inf, 0.0, 0.0)
    assert all(math.isfinite(p["x_m"]) for p in points)


def test_the_trace_is_capped_and_its_last_point_is_the_newest_pose() -> None:
    points: list[dict[str, float]] = []
    for i in range(MAX_TRACE_POINTS + 100):
        add_trace_point(points, i * 0.05, 0.0, 0.0)
    assert len(points) == MAX_TRACE_POINTS
    assert points[-1]["x_m"] == pytest.approx((MAX_TRACE_POINTS + 99) * 0.05)


def test_a_user_predicts_one_plan_at_a_time_and_the_process_at_most_its_cap() -> None:
    slots = PredictionSlots(cap=2)
    slots.take(1)
    with pytest.raises(ApiError) as same_user:
        slots.check(1)
    assert (same_user.value.status, same_user.value.code) == (409, "busy")
    slots.take(2)
    with pytest.raises(ApiError, match="as many plans as it can"):
        slots.take(3)
    slots.release(1)
    slots.take(3)
    with pytest.raises(ApiError):
        PredictionSlots(cap=0).check(9)


def _slot_free(slots: PredictionSlots, user_id: int) -> bool:
    try:
        slots.check(user_id)
    except ApiError:
        return False
    return True


class SlowlyStoppingFarm:
    """A farm whose copy answers nothing (its start fails half-way, leaving the robot) and whose process takes
    a while to end once it has left the farm's list, as a loaded machine's does."""

    def __init__(self, slots: PredictionSlots) -> None:
        self.slots, self.listed, self.stopped = slots, set[str](), False
        self.slot_free_once_unlisted: bool | None = None

    def start(self, spec: RobotSpec) -> None:
        self.listed.add(spec.name)
        raise FarmUnavailable("The copy did not answer.")

    def find(self, name: str) -> object | None:
        return name if name in self.listed else None

    def stop(self, name: str) -> bool:
        self.listed.discard(name)
        self.slot_free_once_unlisted = _slot_free(self.slots, 7)
        time.sleep(0.3)
        self.stopped = True
        return True


def test_the_outcome_comes_once_the_copy_is_stopped_and_the_slot_given_back() -> None:
    """A page that reads the outcome (or sees the copy gone) predicts again at once: it was answered 409 busy while
    the copy's process ended, the slot given back only after it."""
    slots = PredictionSlots(cap=2)
    farm = SlowlyStoppingFarm(slots)
    messages = run_prediction(farm, slots, PredictionRequest(7, "p", {}, "lab", None, True))  # type: ignore[arg-type]
    assert next(messages)["phase"] == "starting" and not _slot_free(slots, 7)
    outcome = next(messages)
    error = outcome["error"]
    assert outcome["type"] == "error" and isinstance(error, dict) and error["code"] == "farm_unavailable", outcome
    assert farm.stopped and not farm.listed, "the outcome came before the copy was stopped"
    assert _slot_free(slots, 7) and farm.slot_free_once_unlisted, "the copy was gone and the user still busy"
    assert next(messages, None) is None


def test_set_watchdog_lines_are_found_in_blocks_and_refused_naming_the_first(skills: SkillSchemas) -> None:
    plan = parse_plan_text('say "a"\nrepeat 2 {\n  if obstacle_within 0.5 {\n    say "b"\n  } else {\n'
                           "    set watchdog 0.5s\n  }\n}\nset watchdog 2s\nset max_speed 0.2\n", skills)
    assert watchdog_lines(plan) == [6, 9]
    check_settings_permitted(plan, may_set_watchdog=True)
    with pytest.raises(ApiError) as refused:
        check_settings_permitted(plan, may_set_watchdog=False)
    assert (refused.value.status, refused.value.code, refused.value.field) == (403, "not_permitted", "watchdog_s")
    assert refused.value.message.startswith("Line 6: your course does not let students set the watchdog")
    check_settings_permitted(parse_plan_text("set max_speed 0.2\n", skills), may_set_watchdog=False)
