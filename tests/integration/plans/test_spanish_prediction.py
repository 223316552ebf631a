"""A Spanish student's prediction speaks Spanish although its stream runs after its request has ended: the copy's
start and where the run starts are said in the person's language (the stream keeps the request's language), and in
English for an English reader as before."""

from __future__ import annotations

import pytest

from tests.integration.plans.conftest import PlansLab, api
from tests.integration.plans.test_plan_predictions import predict, prediction_robots
from tests.integration.plans.test_plan_runs import _create

pytestmark = pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)


def test_a_predictions_sentences_are_in_the_readers_language(plans_lab: PlansLab) -> None:
    ann = plans_lab.client("student1")
    plan_id = _create(ann, "short-hop", "drive 0.2 0 for 1s\n")
    english = predict(ann, plan_id, {"beside": "lab-1", "from_dock": True})
    assert english[0]["message"] == "Starting a simulated copy of lab-1 in the scene lab…", english[0]
    started = next(m for m in english if m["type"] == "started")
    assert started["start"]["message"] == "Starts at its dock.", started["start"]

    assert api(ann, "PUT", "/api/me/preferences/language", {"value": "es"})[0] == 200
    spanish = predict(ann, plan_id, {"beside": "lab-1", "from_dock": True})
    assert spanish[0]["message"] == "Arrancando una copia simulada de lab-1 en la escena lab…", spanish[0]
    started = next(m for m in spanish if m["type"] == "started")
    assert started["start"]["message"] == "Empieza en su base.", started["start"]
    assert spanish[-1]["type"] == "end" and spanish[-1]["goal"]["status"] == "succeeded", spanish[-1]
    assert prediction_robots(plans_lab.server) == [], "the prediction's robot outlived its answer"


def test_a_plans_error_sentences_stay_whole_for_a_spanish_reader(plans_lab: PlansLab) -> None:
    """A parameter out of range reads as one Spanish sentence: the plan's place and the command form's range check
    in the same language, never English words around Spanish ones."""
    ann = plans_lab.client("student1")
    assert api(ann, "PUT", "/api/me/preferences/language", {"value": "es"})[0] == 200
    status, body = api(ann, "POST", "/api/plans/check", {"text": "go_to 120 0"})
    assert status == 200 and body["valid"] is False, body
    expected = "línea 1, columna 7: goal_x_m debe estar entre -50 y 50 m; se recibió 120."
    assert body["errors"][0]["message"] == expected, body
