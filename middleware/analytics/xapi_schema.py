"""Checks an xAPI statement against the 1.0.3 statement schema (xapi-statement.schema.json, written from the
specification's Part Two, section 2.4) and the rules beside it a JSON schema cannot say."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

from jsonschema import Draft202012Validator  # type: ignore[import-untyped]

SCHEMA_PATH = Path(__file__).with_name("xapi-statement.schema.json")


@cache
def _validator() -> Draft202012Validator:
    schema = json.loads(SCHEMA_PATH.read_text())
    Draft202012Validator.check_schema(schema)
    return Draft202012Validator(schema)


def _score_errors(result: Any, where: str) -> list[str]:
    score = result.get("score") if isinstance(result, dict) else None
    if not isinstance(score, dict):
        return []
    low, high, raw = score.get("min"), score.get("max"), score.get("raw")
    errors = []
    if isinstance(low, int | float) and isinstance(high, int | float) and not low < high:
        errors.append(f"{where}.score: min must be less than max (2.4.5.1)")
    if isinstance(raw, int | float):
        if isinstance(low, int | float) and raw < low:
            errors.append(f"{where}.score.raw: below min (2.4.5.1)")
        if isinstance(high, int | float) and raw > high:
            errors.append(f"{where}.score.raw: above max (2.4.5.1)")
    return errors


def statement_errors(statement: Any) -> list[str]:
    """What makes statement invalid, each as 'path: reason'; empty when it is a valid xAPI 1.0.3 statement."""
    errors = [f"{'/'.join(str(p) for p in error.absolute_path) or '(statement)'}: {error.message}"
              for error in sorted(_validator().iter_errors(statement), key=lambda e: list(map(str, e.absolute_path)))]
    if isinstance(statement, dict):
        errors += _score_errors(statement.get("result"), "result")
        sub = statement.get("object")
        if isinstance(sub, dict) and sub.get("objectType") == "SubStatement":
            errors += _score_errors(sub.get("result"), "object.result")
    return errors
