"""A Spanish student reads their exercise run in Spanish over HTTP: the grader's feedback and the measurements' names
(stored in English with the run) are said in the person's language when the run is read, the numbers with the
decimal comma; the same run read in English is word for word what the grader stored. The exercises' and plans'
refusals answer in Spanish too, with the same status, code and field."""

from __future__ import annotations

import time

import pytest

from tests.integration.exercises.test_exercise_api import STILL, wait_for_practice_robot
from tests.integration.plans.conftest import PlansLab, api


def _language(client, language: str) -> None:
    status, answer = api(client, "PUT", "/api/me/preferences/language", {"value": language})
    assert status == 200, answer


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_a_graded_run_reads_in_the_students_language_and_its_english_is_as_stored(plans_lab: PlansLab) -> None:
    ann = plans_lab.client("student1")
    wait_for_practice_robot(ann)
    status, answer = api(ann, "POST", "/api/exercises/bump-and-go/runs", {"code": STILL, "mode": "practice"})
    assert status == 201, answer
    run_id = answer["run"]["id"]
    time.sleep(1.5)  # a few pose-log samples
    status, answer = api(ann, "POST", f"/api/exercise-runs/{run_id}/finish", {})
    assert status == 200 and answer["run"]["status"] == "graded", answer
    english = answer["run"]
    assert english["feedback"].endswith("%)."), english["feedback"]
    assert "of the points. distance driven " in english["feedback"] and "(bar " in english["feedback"]
    assert "floor cells visited 1 cell (bar 14 cells: 0%)" in english["feedback"], english["feedback"]  # agrees
    assert [m["name"] for m in english["measurements"]] == [
        "distance driven", "floor cells visited", "longest time stuck"]

    _language(ann, "es")
    status, answer = api(ann, "GET", f"/api/exercise-runs/{run_id}")
    assert status == 200, answer
    spanish = answer["run"]
    assert [m["name"] for m in spanish["measurements"]] == [
        "distancia recorrida", "casillas del suelo visitadas", "mayor tiempo atascado"]
    assert [m["value"] for m in spanish["measurements"]] == [m["value"] for m in english["measurements"]]
    feedback = spanish["feedback"]
    assert "% de los puntos. distancia recorrida " in feedback, feedback
    assert "visitadas 1 casilla (umbral 14 casillas" in feedback, feedback  # the unit agrees with its number
    assert "of the points" not in feedback and "bar " not in feedback and "," in feedback  # 0,00 m
    status, answer = api(ann, "POST", "/api/exercises/no-such-exercise/runs", {"code": STILL})
    assert (status, answer["error"]["code"], answer["error"]["message"]) == (
        404, "unknown_exercise", "No existe ese ejercicio."), answer
    status, answer = api(ann, "POST", "/api/plans", {"name": "bad name", "text": "stop"})
    assert (status, answer["error"]["field"]) == (400, "name"), answer
    assert answer["error"]["message"] == "El nombre de un plan tiene de 1 a 64 letras, dígitos, - y _ (sin espacios)."

    bea = plans_lab.client("student2")  # no code of her own yet
    _language(bea, "es")
    status, answer = api(bea, "GET", "/api/exercises/bump-and-go")
    assert status == 200 and "# El bucle va a 20 Hz" in answer["code"] and "The loop runs" not in answer["code"], answer
    assert answer["exercise"]["template"] == answer["code"]  # a student without code of their own starts from it
    status, answer = api(plans_lab.client("tutor1"), "GET", "/api/exercises/bump-and-go")
    assert "# The loop runs at 20 Hz" in answer["code"], "an English reader gets the template as stored"

    _language(ann, "en")
    status, answer = api(ann, "GET", f"/api/exercise-runs/{run_id}")
    assert answer["run"]["feedback"] == english["feedback"] and answer["run"]["measurements"] == english["measurements"]
    status, answer = api(ann, "POST", "/api/plans", {"name": "bad name", "text": "stop"})
    assert answer["error"]["message"] == "A plan's name is 1 to 64 letters, digits, - and _ (no spaces).", answer
