"""The plan page's blocks are a view of the text (client_ui/static/pages/plans/blocks-form.js, run in node): every
plan of the demo data and of the plan tests goes text -> blocks -> text IDENTICAL and block -> text -> block
unchanged, and every plan the language writes is all blocks of its own kind, none a raw "line" block, so each
command of the language has its block."""

from __future__ import annotations

import ast
import json
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from middleware.plans import Plan, PlanInvalid, parse_plan_text, plan_from_json, plan_to_json, plan_to_text
from middleware.plans.demo_plans import REACTING_PLAN, SHARED_PLAN, STUDENT_PLAN
from tests.unit.plans.catalogue import catalogue_schemas
from tests.unit.plans.test_plan_properties import plans

ROOT = Path(__file__).resolve().parents[3]
CONVERTER = ROOT / "client_ui/static/pages/plans/blocks-form.js"
HARNESS = Path(__file__).with_name("blocks_roundtrip.mjs")
PLAN_TESTS = [*sorted((ROOT / "tests/unit/plans").glob("test_*.py")), *sorted((ROOT / "tests/integration/plans")
              .glob("test_*.py")), ROOT / "tests/e2e/test_plans.py", ROOT / "tests/e2e/test_plan_blocks.py"]
SKILLS = catalogue_schemas()


class Converter:
    """One node process running the page's converter, asked one text at a time."""

    def __init__(self) -> None:
        node = shutil.which("node")
        if node is None:
            pytest.fail("node is not installed; make test installs it with the vendor libraries")
        self.process = subprocess.Popen([node, str(HARNESS), str(CONVERTER)], stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, text=True, encoding="utf-8")

    def round_trip(self, text: str) -> dict[str, object]:
        """What the converter answers for text."""
        assert self.process.stdin is not None and self.process.stdout is not None
        self.process.stdin.write(json.dumps(text) + "\n")
        self.process.stdin.flush()
        return json.loads(self.process.stdout.readline())


@pytest.fixture(scope="module")
def converter() -> Iterator[Converter]:
    running = Converter()
    yield running
    assert running.process.stdin is not None and running.process.stdout is not None
    running.process.stdin.close()
    running.process.wait(timeout=10)
    running.process.stdout.close()


def texts_of_the_plan_tests() -> list[str]:
    """Every string of the plan tests that holds a line break or reads as a plan, and the demo plans."""
    found = [STUDENT_PLAN[1], REACTING_PLAN[1], SHARED_PLAN[1]]
    for path in PLAN_TESTS:
        if not path.exists():
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (isinstance(node, ast.Constant) and isinstance(node.value, str) and 0 < len(node.value) < 20_000
                    and ("\n" in node.value or _is_plan(node.value))):
                found.append(node.value)
    return list(dict.fromkeys(found))


def _is_plan(text: str) -> bool:
    try:
        parse_plan_text(text, SKILLS)
    except PlanInvalid:
        return False
    return True


TEXTS = texts_of_the_plan_tests()


def test_the_demo_plans_and_the_plan_tests_plans_are_many() -> None:
    assert len(TEXTS) > 100 and STUDENT_PLAN[1] in TEXTS and "on obstacle_detected" in "".join(TEXTS)


def test_every_plan_of_the_demo_and_the_plan_tests_round_trips_identically(converter: Converter) -> None:
    failures = []
    for text in TEXTS:
        answer = converter.round_trip(text)
        if not (answer["text_kept"] and answer["blocks_kept"]):
            failures.append((text, answer["back"]))
    assert not failures, failures[:3]


def test_a_plan_as_the_language_writes_it_is_all_blocks_of_its_own_kind(converter: Converter) -> None:
    written = 0
    for text in TEXTS:
        if _is_plan(text) and plan_to_text(parse_plan_text(text, SKILLS)) == text:
            written += 1
            assert "plan_line" not in converter.round_trip(text)["types"], text
    assert written >= 5


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(plans)
def test_any_plan_the_language_accepts_round_trips_through_its_blocks(converter: Converter, plan: Plan) -> None:
    try:
        checked = plan_from_json(plan_to_json(plan), SKILLS)
    except PlanInvalid:
        return
    text = plan_to_text(checked)
    answer = converter.round_trip(text)
    assert answer["text_kept"] and answer["blocks_kept"], (text, answer["back"])
    assert "plan_line" not in answer["types"], text  # type: ignore[operator]
