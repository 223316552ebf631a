"""Hostile values in every field the exercises' API reads, one field at a time: never a 500, and a 400 names the
field at fault (the hardening suite's table, applied to this area's bodies)."""

from __future__ import annotations

import pytest

from tests.integration.exercises.test_exercise_api import NEW_EXERCISE, STILL
from tests.integration.plans.conftest import PlansLab, api

HOSTILE: tuple[object, ...] = ("²", "1" * 5000, "\ud800", "a\x00b", ["²"], {"type": ["x"]}, 2**63, 1e308, None,
                               True, -1, "x" * 30_000)
BODIES = (
    ("tutor1", "POST", "/api/exercises", NEW_EXERCISE),
    ("tutor1", "PUT", "/api/exercises/bump-and-go", {k: v for k, v in NEW_EXERCISE.items() if k != "slug"}),
    ("student1", "POST", "/api/exercises/bump-and-go/codes", {"code": STILL}),
    ("student1", "POST", "/api/exercises/bump-and-go/runs", {"code": STILL, "mode": "practice", "robot": "practice"}),
    ("student1", "POST", "/api/exercise-runs/1/finish", {"report": {"x_m": 1.0, "y_m": 2.0, "t_s": 3.0}}),
)
NESTED = {"rubric": ("kind", "x_m", "radius_m"), "random_starts": ("x_m",), "report": ("x_m", "t_s")}


def variants(body: dict[str, object]):
    for field in body:
        for hostile in HOSTILE:
            yield field, {**body, field: hostile}
        for inner in NESTED.get(field, ()):
            for hostile in HOSTILE[:8]:
                yield f"{field}.{inner}", {**body, field: {**body[field], inner: hostile}}  # type: ignore[dict-item]


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_every_field_refuses_hostile_values_naming_it_and_never_answers_500(plans_lab: PlansLab) -> None:
    clients = {name: plans_lab.client(name) for name in ("tutor1", "student1")}
    unnamed, failures, tried = [], [], 0
    for who, method, path, body in BODIES:
        for field, changed in variants(body):
            tried += 1
            status, answer = api(clients[who], method, path, changed)
            if status >= 500:
                failures.append(f"{method} {path} {field}: {status} {answer}")
            elif status == 400 and not (answer.get("error") or {}).get("field"):
                unnamed.append(f"{method} {path} {field}: {answer}")
    assert not failures, failures[:10]
    assert not unnamed, unnamed[:10]
    assert tried > 150
