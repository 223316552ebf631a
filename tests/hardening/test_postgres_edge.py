"""The int64 and text cases on PostgreSQL, which is stricter than SQLite: it refuses NUL in text, and its
integer columns are 32 or 64 bits. Every rule with an id, at int32's maximum (the largest URL id), and every body
with numbers past int32 and NUL in text: never a 500."""

from __future__ import annotations

import json

import pytest

from tests.hardening.conftest import logged_in_client, seeded_lab, stop_lab
from tests.hardening.test_hostile_input import BODY_METHODS, FIELDS, Tally, fill_path, form_body, routes

INT32_MAX_ID = str(2**31 - 1)  # the largest id a URL may carry; the tables hold it
PAST_INT32 = (2**31, 2**40, 2**63 - 1, -(2**63))


@pytest.mark.postgres
def test_no_rule_answers_500_on_postgresql(postgres_url: str, tmp_path) -> None:
    app = seeded_lab(postgres_url, tmp_path)
    tally = Tally()
    try:
        for role in ("student", "tutor", "admin"):
            client = logged_in_client(app, role)
            for method, rule in routes():
                if "<int:" in rule:
                    tally.send(client, role, method, fill_path(rule, INT32_MAX_ID, "lab-1"), None, None)
                destructive = method == "DELETE" or rule.endswith(("/delete", "/remove", "/revoke"))
                if method not in BODY_METHODS or destructive:
                    continue
                url = fill_path(rule, "1", "lab-1")
                numbers = {name: PAST_INT32[i % len(PAST_INT32)] for i, name in enumerate(FIELDS)}
                tally.send(client, role, method, url, json.dumps(numbers).encode(), "application/json")
                texts = {name: f"text\x00{name}" for name in FIELDS}
                tally.send(client, role, method, url, json.dumps(texts).encode(), "application/json")
                tally.send(client, role, method, url, form_body({k: str(v) for k, v in numbers.items()}),
                           "application/x-www-form-urlencoded")
    finally:
        stop_lab(app)
    tally.record("postgresql")
    assert not tally.failures, f"{len(tally.failures)} answers were 500:\n" + "\n".join(tally.failures[:40])
