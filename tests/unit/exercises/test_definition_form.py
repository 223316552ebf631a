"""The catalogue's form asks for each rubric kind's numbers from schemas.RUBRIC_PARAMETERS: those are the numbers the
API requires (a rubric without one is refused naming it), the optional ones are those the API accepts, and the
default the form says the grader takes is the one it takes. "new" is no slug: /exercises/new is the form."""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest
from flask import Flask
from flask_babel import Babel  # type: ignore[import-untyped]

from middleware.auth.schemas import InvalidField
from middleware.exercises import grading, schemas
from middleware.exercises.catalogue import BUILT_IN

# 30 s at 5 samples a second around a circle of 0.7 m near the lab's centre (0.15 m/s): every optional number moves
# some measurement of it (the cells it visits, how long it stays within a radius, the distance to a wall after a time).
TRACE = [[i / 5, 0.13 + 0.7 * math.cos(i / 5 * 0.21), 0.07 + 0.7 * math.sin(i / 5 * 0.21), 0.0, 0.0, 0.0, 0.0]
         for i in range(150)]


@pytest.fixture(autouse=True)
def request_context() -> Iterator[None]:
    app = Flask(__name__)
    Babel(app)
    with app.test_request_context():
        yield


def definition(rubric: dict[str, object], slug: str = "a-new-one") -> dict[str, object]:
    return {"slug": slug, "title": "T", "statement": "", "template": "", "scene": "lab", "start": [0, 0, 0],
            "random_starts": None, "time_limit_s": 30, "rubric": rubric}


def test_the_form_describes_every_rubric_kind_with_the_apis_numbers() -> None:
    assert tuple(schemas.RUBRIC_PARAMETERS) == grading.RUBRIC_KINDS == tuple(schemas.RUBRIC_KIND_NAMES)
    for kind, numbers in schemas.RUBRIC_PARAMETERS.items():
        assert len({n.name for n in numbers}) == len(numbers), kind
        assert all(n.unit in ("m", "s", "cells", "") and n.label and n.hint for n in numbers), kind
        assert {n.name for n in numbers if n.optional} <= set(schemas.OPTIONAL_NUMBERS), kind
        required = [n.name for n in numbers if not n.optional]
        rubric = {"kind": kind, **{name: 1.0 for name in required}}
        if kind in ("cover_room", "follow_line"):
            rubric.update(x_min_m=-1.0, x_max_m=1.0, y_min_m=-1.0, y_max_m=1.0, corner_radius_m=0.2)
        assert schemas.definition(definition(rubric))["rubric"]["kind"] == kind
        for name in required:  # each one the form shows as required is one the API requires
            with pytest.raises(InvalidField) as refused:
                schemas.definition(definition({k: v for k, v in rubric.items() if k != name}))
            assert refused.value.field == f"rubric.{name}"


@pytest.mark.parametrize("entry", [e for e in BUILT_IN if e["rubric"]["kind"] in ("bump_and_go", "wall_following",
                                                                                    "cover_room")],
                         ids=lambda e: e["slug"])
def test_an_optional_number_left_empty_grades_as_the_default_the_form_names(entry: dict) -> None:
    rubric = dict(entry["rubric"])
    for number in schemas.RUBRIC_PARAMETERS[rubric["kind"]]:
        if number.optional:
            rubric[number.name] = number.default
            without = {k: v for k, v in rubric.items() if k != number.name}
            assert grading.grade(without, TRACE).measurements == grading.grade(rubric, TRACE).measurements, \
                number.name


def test_new_is_no_exercises_slug() -> None:
    with pytest.raises(InvalidField) as refused:
        schemas.definition(definition({"kind": "report_pose", "tolerance_m": 0.3}, slug="new"))
    assert refused.value.field == "slug"
    assert schemas.definition(definition({"kind": "report_pose", "tolerance_m": 0.3}, slug="news"))["slug"] == "news"
