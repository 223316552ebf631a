"""Validation of questions, bank files, exams and survey answers; every error names the item and the field."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.assessment import obstacle_zone
from middleware.assessment.grading import QUESTION_KINDS, UNITS
from middleware.assessment.rating import read_ends
from middleware.assessment.survey_statements import (  # noqa: F401  (AGREEMENT, SURVEY_ITEMS: read from here too)
    AGREEMENT,
    FIXED_STATEMENTS,
    SURVEY_ITEMS,
    Statement,
    parse_answers,
)
from middleware.assessment.trace_grading import DEFAULT_RUBRIC, TASK_KINDS
from middleware.auth.schemas import InvalidField
from middleware.validation import InvalidInput, decimal_int, loads_checked, within_calendar

MAX_BANK_BYTES = 512 * 1024
MAX_BANK_QUESTIONS = 500
MAX_CHOICES = 12
EXAM_KINDS = ("quiz", "theory", "experimental")
BANK_FORMAT = "telelab-question-bank/1"


def _text(value: object, field: str, max_length: int, required: bool = True) -> str:
    if value is None and not required:
        return ""
    if not isinstance(value, str) or (required and not value.strip()) or len(value) > max_length:
        raise InvalidField(field, gettext("%(field)s must be text of 1 to %(max_length)s characters.", field=field,
                                          max_length=max_length))
    return value.strip()


def _number(value: object, field: str, low: float = -1e9, high: float = 1e9) -> float:
    if isinstance(value, str):
        try:
            value = float(value.strip())
        except ValueError:
            raise InvalidField(field, gettext("%(field)s must be a number.", field=field)) from None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) \
            or not low <= value <= high:
        raise InvalidField(field, gettext("%(field)s must be a number from %(low)s to %(high)s.", field=field,
                                          low=format(low, 'g'), high=format(high, 'g')))
    return float(value)


def _topics(value: object) -> list[str]:
    if isinstance(value, str):
        value = [t for t in (part.strip() for part in value.split(",")) if t]
    if not isinstance(value, list) or len(value) > 10:
        raise InvalidField("topics", gettext("topics must be a list of at most 10 short names."))
    return sorted({_text(t, "topics", 60).lower() for t in value})


def _choices(value: object) -> list[str]:
    if isinstance(value, str):
        value = [line.strip() for line in value.splitlines() if line.strip()]
    if not isinstance(value, list) or not 2 <= len(value) <= MAX_CHOICES:
        raise InvalidField("choices", gettext("choices must be 2 to %(max_choices)s options.", max_choices=MAX_CHOICES))
    return [_text(c, "choices", 300) for c in value]


def _index_list(value: object, count: int, field: str) -> list[int]:
    if isinstance(value, str):
        value = [part.strip() for part in value.split(",") if part.strip()]
    if isinstance(value, int) and not isinstance(value, bool):
        value = [value]
    if not isinstance(value, list) or not value:
        raise InvalidField(field, gettext("%(field)s must name at least one choice by its number (0 is the first).",
                                          field=field))
    out = []
    for item in value:
        item = decimal_int(item) if isinstance(item, str) else item
        if isinstance(item, bool) or not isinstance(item, int) or not 0 <= item < count:
            raise InvalidField(field, gettext("%(field)s must be choice numbers from 0 to %(value)s.", field=field,
                                              value=count - 1))
        out.append(item)
    return sorted(set(out))


@dataclass(frozen=True)
class QuestionInput:
    """A validated question."""

    kind: str
    prompt: str
    topics: list[str]
    spec: dict[str, Any]
    points: float

    def to_dict(self) -> dict[str, Any]:
        """The bank file's form of the question."""
        return {"kind": self.kind, "prompt": self.prompt, "topics": self.topics, "points": self.points, **self.spec}


def form_choice_numbers(value: object, choices: object) -> list[int]:
    """The bank editor's right choices, numbered from 1 as the person reads them, as the 0-based list
    parse_question takes; errors name the field `correct` in the form's own numbering."""
    count = len(_choices(choices))
    tokens = [part.strip() for part in str(value or "").split(",") if part.strip()]
    if not tokens:
        raise InvalidField("correct", gettext("Give the number of the right choice (1 is the first line)."))
    numbers = [decimal_int(token, 1, count) for token in tokens]
    if any(number is None for number in numbers):
        raise InvalidField("correct", gettext("Right choices are numbers from 1 to %(count)s, one per right line, "
                                              "e.g. 1, 3.", count=count))
    return [number - 1 for number in numbers if number is not None]


def parse_question(data: dict[str, Any]) -> QuestionInput:
    """A question from JSON or a form: kind, prompt, topics, points and the kind's own fields."""
    kind = data.get("kind")
    if kind not in QUESTION_KINDS:
        raise InvalidField("kind", gettext("kind must be one of %(value)s.", value=', '.join(QUESTION_KINDS)))
    prompt = _text(data.get("prompt"), "prompt", 4000)
    topics = _topics(data.get("topics") or [])
    points = _number(data.get("points", 1) or 1, "points", 0.1, 100)
    spec: dict[str, Any]
    if kind in ("single", "multiple"):
        choices = _choices(data.get("choices"))
        correct = _index_list(data.get("correct"), len(choices), "correct")
        if kind == "single":
            if len(correct) != 1:
                raise InvalidField("correct", gettext("correct must name exactly one choice for a single-choice "
                                                      "question."))
            spec = {"choices": choices, "correct": correct[0]}
        else:
            spec = {"choices": choices, "correct": correct}
    elif kind == "numeric":
        unit = _text(data.get("unit"), "unit", 16, required=False)
        if unit and unit not in UNITS:
            raise InvalidField("unit", gettext("unit must be empty or one of %(value)s.", value=', '.join(UNITS)))
        spec = {"value": _number(data.get("value"), "value"),
                "tolerance": _number(data.get("tolerance", 0) or 0, "tolerance", 0, 1e9), "unit": unit}
    elif kind == "rating":
        spec = read_ends(data)
    else:
        accepted = data.get("accepted")
        if isinstance(accepted, str):
            accepted = [line.strip() for line in accepted.splitlines() if line.strip()]
        if not isinstance(accepted, list) or not 1 <= len(accepted) <= 20:
            raise InvalidField("accepted", gettext("accepted must list 1 to 20 accepted answers."))
        spec = {"accepted": [_text(a, "accepted", 300) for a in accepted],
                "case_sensitive": data.get("case_sensitive") in (True, "1", "on", "true")}
    return QuestionInput(kind, prompt, topics, spec, points)


def parse_bank_file(data: bytes) -> list[QuestionInput]:
    """The questions of a bank file; every invalid item is reported as 'question N: field: message'."""
    if len(data) > MAX_BANK_BYTES:
        raise InvalidField("file", gettext("The file is larger than %(value)s KiB.", value=MAX_BANK_BYTES // 1024))
    try:
        document = loads_checked(data.decode("utf-8-sig"))
    except (UnicodeDecodeError, ValueError) as error:
        raise InvalidField("file", gettext("The file is not UTF-8 JSON (%(error)s).", error=error)) from None
    except InvalidInput as refused:
        raise InvalidField("file", gettext("The file cannot be imported: %(message)s",
                                           message=refused.message)) from None
    items = document.get("questions") if isinstance(document, dict) else None
    if not isinstance(items, list):
        raise InvalidField("file", gettext("The file must be a JSON object with a \"questions\" list."))
    if len(items) > MAX_BANK_QUESTIONS:
        raise InvalidField("file", gettext("The file holds more than %(max_bank_questions)s questions.",
                                           max_bank_questions=MAX_BANK_QUESTIONS))
    parsed, problems = [], []
    for number, item in enumerate(items, start=1):
        try:
            if not isinstance(item, dict):
                raise InvalidField("question", gettext("each question must be a JSON object."))
            parsed.append(parse_question(item))
        except InvalidField as invalid:
            problems.append(f"question {number}: {invalid.field}: {invalid.message}")
    if problems:
        raise InvalidField("file", "; ".join(problems[:20]) + (" …" if len(problems) > 20 else ""))
    return parsed


def parse_moment(value: object, field: str) -> datetime | None:
    """An ISO 8601 moment (naive means UTC), or None when empty."""
    if value in (None, ""):
        return None
    if not isinstance(value, str):
        raise InvalidField(field, gettext("%(field)s must be a date and time such as 2026-05-04T09:00.", field=field))
    try:
        moment = datetime.fromisoformat(value.strip().replace("Z", "+00:00"))
    except ValueError:
        raise InvalidField(field, gettext("%(field)s must be a date and time such as 2026-05-04T09:00.",
                                          field=field)) from None
    if not within_calendar(moment):
        raise InvalidField(field, gettext("%(field)s must be a date between the years 1900 and 9000.", field=field))
    return moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)


RUBRIC_ROWS = 5


def form_rubric(form: dict[str, Any]) -> object:
    """The test editor's rubric rows ("error up to B m earns S % of the points") as the bands parse_rubric takes;
    a form without rows (the API's, older pages) keeps its `rubric` as sent. Every bad row is named at once."""
    if not any(key.startswith("rubric_bound_") for key in form):
        return form.get("rubric")
    bands, problems = [], []
    for row in range(RUBRIC_ROWS):
        bound, share = (str(form.get(f"rubric_{part}_{row}") or "").strip() for part in ("bound", "share"))
        if not bound and not share:
            continue
        try:
            bands.append([float(bound), float(share) / 100])
        except ValueError:
            problems.append(gettext("row %(row)s needs an error bound in metres and a share in percent", row=row + 1))
    if problems:
        raise InvalidField("rubric", gettext("Rubric: %(value)s.", value='; '.join(problems)))
    return bands or None


def parse_rubric(value: object) -> list[list[float]]:
    """Bands [[error_bound_m, fraction], ...]: bounds positive and increasing, fractions 0-1 and decreasing."""
    if value in (None, "", []):
        return DEFAULT_RUBRIC
    if isinstance(value, str):
        try:
            value = [[float(x) for x in band.split(":")] for band in value.split(",") if band.strip()]
        except ValueError:
            raise InvalidField("rubric", gettext("rubric must be bands like 0.1:1, 0.2:0.5 (bound in m: "
                                                 "fraction).")) from None
    if not isinstance(value, list) or not 1 <= len(value) <= 10:
        raise InvalidField("rubric", gettext("rubric must be 1 to 10 bands [bound_m, fraction]."))
    bands = []
    for band in value:
        if not isinstance(band, list | tuple) or len(band) != 2:
            raise InvalidField("rubric", gettext("each rubric band is [bound_m, fraction]."))
        bands.append([_number(band[0], "rubric", 0.001, 100), _number(band[1], "rubric", 0, 1)])
    bands.sort()
    if any(b[1] > a[1] for a, b in zip(bands, bands[1:], strict=False)):
        raise InvalidField("rubric", gettext("a wider band cannot give more credit than a narrower one."))
    return bands


def parse_task(data: dict[str, Any]) -> dict[str, Any]:
    """An experimental task with its rubric and points."""
    kind = data.get("task_kind") or data.get("kind")
    if kind not in TASK_KINDS:
        raise InvalidField("task_kind", gettext("task_kind must be one of %(value)s.", value=', '.join(TASK_KINDS)))
    task: dict[str, Any] = {"kind": kind, "rubric": parse_rubric(data.get("rubric")),
                            "points": _number(data.get("task_points", data.get("points", 10)) or 10,
                                              "task_points", 0.1, 100),
                            "topics": _topics(data.get("task_topics") or []),
                            "instructions": _text(data.get("instructions") or "", "instructions", 2000, False)}
    if kind == "reach_point":
        task.update(x_m=_number(data.get("x_m"), "x_m", -50, 50), y_m=_number(data.get("y_m"), "y_m", -50, 50))
    elif kind == "wall_following":
        for name in ("x1_m", "y1_m", "x2_m", "y2_m"):
            task[name] = _number(data.get(name), name, -50, 50)
        task["distance_m"] = _number(data.get("distance_m"), "distance_m", 0.05, 5)
        task["min_travel_m"] = _number(data.get("min_travel_m", 1.0) or 1.0, "min_travel_m", 0, 50)
    elif kind == obstacle_zone.TASK_KIND and data.get("rubric") in (None, "", []):
        task["rubric"] = obstacle_zone.ZONE_RUBRIC  # bands on 1 - IoU, not metres
    return task


@dataclass(frozen=True)
class ExamInput:
    """A validated exam."""

    title: str
    kind: str
    opens_at: datetime | None
    closes_at: datetime | None
    duration_s: int | None
    max_attempts: int | None
    question_ids: list[int]
    task: dict[str, Any] | None
    robot_name: str | None


def parse_exam(data: dict[str, Any]) -> ExamInput:
    """An exam from JSON or a form. Timed tests need a window and a duration; quizzes need neither."""
    title = _text(data.get("title"), "title", 200)
    kind = data.get("kind")
    if kind not in EXAM_KINDS:
        raise InvalidField("kind", gettext("kind must be one of %(value)s.", value=', '.join(EXAM_KINDS)))
    opens_at, closes_at = parse_moment(data.get("opens_at"), "opens_at"), parse_moment(data.get("closes_at"),
                                                                                        "closes_at")
    duration = data.get("duration_s")
    duration_s = None if duration in (None, "") else int(_number(duration, "duration_s", 10, 86400))
    if kind != "quiz":
        if opens_at is None or closes_at is None:
            raise InvalidField("opens_at" if opens_at is None else "closes_at",
                               gettext("A timed test needs both an opening and a closing time."))
        if duration_s is None:
            raise InvalidField("duration_s", gettext("A timed test needs a duration per attempt (10 s to 24 h)."))
    if opens_at and closes_at and closes_at <= opens_at:
        raise InvalidField("closes_at", gettext("closes_at must be after opens_at."))
    attempts = data.get("max_attempts")
    max_attempts = (None if kind == "quiz" and attempts in (None, "") else
                    int(_number(attempts if attempts not in (None, "") else 1, "max_attempts", 1, 100)))
    raw_ids = data.get("question_ids") or []
    if isinstance(raw_ids, str):
        raw_ids = [part for part in raw_ids.replace(",", " ").split() if part]
    if not isinstance(raw_ids, list) or len(raw_ids) > 200:
        raise InvalidField("question_ids", gettext("question_ids must be a list of at most 200 question ids."))
    ids = []
    for value in raw_ids:
        value = decimal_int(value, 1)
        if value is None:
            raise InvalidField("question_ids", gettext("question_ids must be whole numbers."))
        if value not in ids:
            ids.append(value)
    task = parse_task(data) if kind == "experimental" else None
    if kind != "experimental" and not ids:
        raise InvalidField("question_ids", gettext("Choose at least one question from the bank."))
    robot = _text(data.get("robot_name") or "lab-1", "robot_name", 64) if kind == "experimental" else None
    return ExamInput(title, kind, opens_at, closes_at, duration_s, max_attempts, ids, task, robot)


def parse_survey(data: dict[str, Any],
                 statements: Sequence[Statement] = FIXED_STATEMENTS) -> tuple[dict[str, int], str]:
    """Ratings 1-5 for every statement of the course's survey (the fixed seven by default), and comments."""
    return parse_answers(data, statements)
