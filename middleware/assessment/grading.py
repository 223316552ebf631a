"""Automatic grading of bank questions: pure functions of (question kind, spec, points, answer) -> ItemResult.

Rules, stated once:
- An empty answer (None, "", [], a numeric answer without a value) scores 0 with the feedback "No answer.".
- single: full marks for the keyed choice only.
- multiple: full marks for exactly the keyed set; otherwise (right picks - wrong picks) / keyed picks, never
  below 0, so ticking every box earns nothing.
- numeric: |answer - value| <= tolerance (bounds included; a 1e-9 relative slack absorbs float noise). When the
  question has a unit, a bare number is read in that unit (the page says so); a unit given must be of the same
  quantity (m, cm, mm; rad, deg; s, ms; m/s, cm/s) and is converted before comparing; an unknown unit or one of
  another quantity scores 0 and says so. NaN and infinities score 0.
- text: accepted answers compared after trimming, collapsing spaces and (unless case_sensitive) case folding.
- rating: an opinion on the 1-5 scale, not a right or wrong answer: it is stored and shown, and earns nothing
  out of nothing (0/0), so it never moves a mark.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from middleware.assessment.rating import rating_or_none
from middleware.validation import decimal_int

QUESTION_KINDS = ("single", "multiple", "numeric", "text", "rating")

# unit -> (quantity, factor to the quantity's base unit)
UNITS: dict[str, tuple[str, float]] = {
    "m": ("length", 1.0), "cm": ("length", 0.01), "mm": ("length", 0.001),
    "rad": ("angle", 1.0), "deg": ("angle", math.pi / 180), "°": ("angle", math.pi / 180),
    "s": ("time", 1.0), "ms": ("time", 0.001),
    "m/s": ("speed", 1.0), "cm/s": ("speed", 0.01),
    "rad/s": ("angular_speed", 1.0), "deg/s": ("angular_speed", math.pi / 180),
}


@dataclass(frozen=True)
class ItemResult:
    """The automatic mark of one item (a question or an experimental task)."""

    item: str
    points: float
    max_points: float
    correct: bool
    feedback: str
    topics: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """The JSON form stored in the attempt."""
        data = asdict(self)
        data["topics"] = list(self.topics)
        return data


def _empty(answer: object) -> bool:
    if answer is None:
        return True
    if isinstance(answer, str):
        return not answer.strip()
    if isinstance(answer, list | tuple | set):
        return len(answer) == 0
    if isinstance(answer, dict):
        return _empty(answer.get("value"))
    return False


def parse_number(text: object) -> float | None:
    """A finite number from a number or a string ("0,25" accepted); None when it is not one."""
    if isinstance(text, bool):
        return None
    if isinstance(text, int | float):
        value = float(text)
    elif isinstance(text, str):
        try:
            value = float(text.strip().replace(",", ".").replace("\u2212", "-"))
        except ValueError:
            return None
    else:
        return None
    return value if math.isfinite(value) else None


def _grade_single(spec: dict[str, Any], answer: object) -> tuple[float, str]:
    answer = decimal_int(answer) if isinstance(answer, str) else answer
    if isinstance(answer, bool) or not isinstance(answer, int):
        return 0.0, "The answer is not one of the choices."
    if answer == spec["correct"]:
        return 1.0, "Correct."
    return 0.0, f"The right choice was: {spec['choices'][spec['correct']]}."


def _grade_multiple(spec: dict[str, Any], answer: object) -> tuple[float, str]:
    if not isinstance(answer, list | tuple):
        return 0.0, "The answer is not a set of choices."
    picked: set[int] = set()
    for value in answer:
        value = decimal_int(value) if isinstance(value, str) else value
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < len(spec["choices"]):
            return 0.0, "The answer names a choice that does not exist."
        picked.add(value)
    keyed = set(spec["correct"])
    if picked == keyed:
        return 1.0, "Correct."
    fraction = max(0.0, (len(picked & keyed) - len(picked - keyed)) / len(keyed))
    right = ", ".join(spec["choices"][i] for i in sorted(keyed))
    prefix = "Partly right; the" if fraction else "The"
    return fraction, f"{prefix} right choices were: {right}."


def convert(value: float, unit: str, to_unit: str) -> float | None:
    """value in unit expressed in to_unit, or None when the units are unknown or of different quantities."""
    source, target = UNITS.get(unit.strip()), UNITS.get(to_unit.strip())
    if source is None or target is None or source[0] != target[0]:
        return None
    return value * source[1] / target[1]


def _grade_numeric(spec: dict[str, Any], answer: object) -> tuple[float, str]:
    raw, unit = (answer.get("value"), str(answer.get("unit") or "")) if isinstance(answer, dict) else (answer, "")
    value = parse_number(raw)
    if value is None:
        return 0.0, "The answer is not a number."
    expected_unit = str(spec.get("unit") or "")
    if expected_unit and unit.strip():
        converted = convert(value, unit, expected_unit)
        if converted is None:
            return 0.0, f"{unit.strip()} is not a unit of the same quantity as {expected_unit}."
        value = converted
    target, tolerance = float(spec["value"]), float(spec.get("tolerance", 0.0))
    slack = 1e-9 * max(1.0, abs(target))
    shown = f"{spec['value']:g} ± {tolerance:g} {expected_unit}".strip()
    if abs(value - target) <= tolerance + slack:
        return 1.0, f"Correct ({shown})."
    return 0.0, f"Outside the accepted range ({shown})."


def _normalise(text: str, case_sensitive: bool) -> str:
    collapsed = " ".join(text.split())
    return collapsed if case_sensitive else collapsed.casefold()


def _grade_text(spec: dict[str, Any], answer: object) -> tuple[float, str]:
    if not isinstance(answer, str):
        return 0.0, "The answer is not text."
    case_sensitive = bool(spec.get("case_sensitive", False))
    accepted = {_normalise(a, case_sensitive) for a in spec["accepted"]}
    if _normalise(answer, case_sensitive) in accepted:
        return 1.0, "Correct."
    return 0.0, f"An accepted answer: {spec['accepted'][0]}."


_GRADERS = {"single": _grade_single, "multiple": _grade_multiple, "numeric": _grade_numeric, "text": _grade_text}


def grade_question(item: str, kind: str, spec: dict[str, Any], points: float, answer: object,
                   topics: tuple[str, ...] = ()) -> ItemResult:
    """The mark of one answer to one question (see the module's rules)."""
    if kind == "rating":
        rating = rating_or_none(answer)
        return ItemResult(item, 0.0, 0.0, rating is not None,
                          "No rating." if rating is None else f"Rated {rating} of 5 (not marked).", topics)
    if kind not in _GRADERS:
        raise ValueError(f"unknown question kind {kind!r}")
    if _empty(answer):
        return ItemResult(item, 0.0, points, False, "No answer.", topics)
    fraction, feedback = _GRADERS[kind](spec, answer)
    return ItemResult(item, round(points * fraction, 4), points, fraction >= 1.0, feedback, topics)
