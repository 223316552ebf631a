"""A plan with two errors, checked and saved by a student whose browser asks for Spanish (Accept-Language, no
preference of their own), reads its errors in Spanish with their lines and columns; the same plan from an English
browser reads them in English word for word as before, with the same places, fields and status."""

from __future__ import annotations

import json
from urllib.request import Request

import pytest

from tests.conftest import LabClient
from tests.integration.plans.conftest import PlansLab

pytestmark = pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)

PLAN = 'say "hola"\ngo_to 120 0\nset max_sped 0.3\n'
SPANISH = {
    "check": ["línea 2, columna 7: goal_x_m debe estar entre -50 y 50 m; se recibió 120.",
              "línea 3, columna 5: 'max_sped' no es un ajuste (¿querías decir max_speed?); usa max_speed, "
              "max_turn_rate, watchdog."],
    "summary": "línea 2, columna 7: goal_x_m debe estar entre -50 y 50 m; se recibió 120. (y 1 problema más)",
}
ENGLISH = {
    "check": ["line 2, column 7: goal_x_m must be between -50 and 50 m; got 120.",
              "line 3, column 5: 'max_sped' is not a setting (did you mean max_speed?); use max_speed, max_turn_rate, "
              "watchdog."],
    "summary": "line 2, column 7: goal_x_m must be between -50 and 50 m; got 120. (and 1 more problem)",
}
PLACES = [(2, 7, "steps[1].parameters.goal_x_m"), (3, 5, "steps[2].setting")]


def post(client: LabClient, path: str, body: object, language: str) -> tuple[int, dict]:
    """A JSON POST as the plan page sends it, from a browser asking for language."""
    headers = {"X-CSRFToken": client.csrf_token("/plans"), "Accept": "application/json",
               "Content-Type": "application/json", "Accept-Language": language}
    request = Request(client.base_url + path, data=json.dumps(body).encode(), method="POST", headers=headers)
    try:
        with client._opener.open(request, timeout=60) as response:
            return response.status, json.loads(response.read())
    except Exception as error:
        if hasattr(error, "code"):
            return error.code, json.loads(error.read() or b"{}")
        raise


@pytest.mark.parametrize(("language", "expected"), [("es-ES,es;q=0.9,en;q=0.5", SPANISH), ("en-GB,en;q=0.9", ENGLISH)],
                         ids=["spanish", "english"])
def test_a_plans_two_errors_read_in_the_browsers_language(plans_lab: PlansLab, language: str,
                                                          expected: dict[str, object]) -> None:
    student = plans_lab.client("student2")
    status, checked = post(student, "/api/plans/check", {"text": PLAN}, language)
    assert status == 200 and checked["valid"] is False, checked
    assert [error["message"] for error in checked["errors"]] == expected["check"], checked
    assert [(e["line"], e["column"], e["field"]) for e in checked["errors"]] == PLACES, checked

    status, saved = post(student, "/api/plans", {"name": "two-slips", "text": PLAN}, language)
    assert status == 400 and saved["error"]["code"] == "invalid_plan", saved
    assert saved["error"]["message"] == expected["summary"], saved
    assert saved["error"]["field"] == PLACES[0][2], saved
    assert [error["message"] for error in saved["errors"]] == expected["check"], saved
