"""A plan's error sentences in the reader's language: whole Spanish sentences under a Spanish request (the place,
the problem and the command form's range check in one language; keywords, skill names and field paths as written),
the same English as before under an English one and outside any request (a plan run, a CLI), where gettext has no
language to ask for."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from flask import Flask
from flask_babel import Babel, force_locale  # type: ignore[import-untyped]

from middleware.plans.language import parse_plan_text, plan_from_json
from middleware.plans.steps import PlanInvalid
from middleware.teaching.command_form import SkillSchemas

TRANSLATIONS = Path(__file__).resolve().parents[3] / "middleware" / "translations"
TWO_PROBLEMS = 'say "hola"\ngo_to 120 0\nset max_sped 0.3\n'


@pytest.fixture(scope="module")
def app() -> Flask:
    """A bare app with the lab's real catalogues (the middleware's own Babel set-up, without its database)."""
    app = Flask(__name__)
    Babel(app, default_translation_directories=str(TRANSLATIONS))
    return app


@pytest.fixture
def spanish(app: Flask) -> Iterator[None]:
    with app.test_request_context(), force_locale("es"):
        yield


def refused(text: str, skills: SkillSchemas) -> PlanInvalid:
    with pytest.raises(PlanInvalid) as raised:
        parse_plan_text(text, skills)
    return raised.value


def json_refused(doc: object, skills: SkillSchemas) -> PlanInvalid:
    with pytest.raises(PlanInvalid) as raised:
        plan_from_json(doc, skills)
    return raised.value


@pytest.mark.usefixtures("spanish")
def test_a_plans_errors_read_in_spanish_with_their_places(skills: SkillSchemas) -> None:
    invalid = refused(TWO_PROBLEMS, skills)
    assert [error.message for error in invalid.errors] == [
        "línea 2, columna 7: goal_x_m debe estar entre -50 y 50 m; se recibió 120.",
        "línea 3, columna 5: 'max_sped' no es un ajuste (¿querías decir max_speed?); usa max_speed, max_turn_rate, "
        "watchdog.",
    ]
    assert invalid.message == "línea 2, columna 7: goal_x_m debe estar entre -50 y 50 m; se recibió 120. " \
                              "(y 1 problema más)"
    assert [(error.line, error.column, error.field) for error in invalid.errors] == [
        (2, 7, "steps[1].parameters.goal_x_m"), (3, 5, "steps[2].setting")]


@pytest.mark.usefixtures("spanish")
@pytest.mark.parametrize(("text", "expected"), [
    ("go_to 1m 90deg", "línea 1, columna 10: goal_y_m es una distancia en m; 90deg es un ángulo. Usa m, cm."),
    # a range in the plan's numbers (3.14159, not the Spanish 3,14159 a student would copy and see refused)
    ("turn_to 10", "línea 1, columna 9: heading_rad debe estar entre -3.14159 y 3.14159 rad; se recibió 10."),
    ("repeat 0 {\n  say \"x\"\n}", "línea 1, columna 8: count debe estar entre 1 y 100; se recibió 0."),
    ("localization particle_count=2.5", "línea 1, columna 29: particle_count debe ser un número entero; se recibió "
                                        "2.5."),
    ("wait 3m", "línea 1, columna 6: una duración es un tiempo en s; 3m es una distancia. Usa s, ms."),
    ("repeat 2 {\n}", "línea 1, columna 1: este repeat no tiene nada en su bloque."),
    ("say \"a\tb\"", "línea 1, columna 7: en un texto, no se admite un tabulador; escribe espacios."),
    ("wait 1\n}", "línea 2, columna 1: esta } no cierra ningún bloque; quítala."),
    ("GO_TO 1 2", "línea 1, columna 1: 'GO_TO' no es una orden ni una habilidad de este robot (¿querías decir go_to? "
                  "los nombres se escriben en minúsculas); órdenes: drive, wait, wait_until, repeat, if, on, set, say, "
                  "go_to, turn_to, follow_wall; habilidades que un plan puede ejecutar (las que mueven las ruedas): "
                  "detect_obstacle, direct_control, environment_modelling, go_to_goal, localization, "
                  "orientation_control, round_trip, wall_following."),
    ("go_to 1 2 3", "línea 1, columna 11: go_to lleva como mucho 2 valores sin nombre (goal_x_m, goal_y_m), como en "
                    "go_to 1.2 0.5."),
    ("on wall_lost {\n  say \"x\"\n}", "línea 1, columna 1: este on no atiende nada: vigila las líneas que lo siguen "
                                      "en su bloque, y no sigue ninguna. Ponlo delante de ellas."),
    ("", "steps: el plan está vacío: escribe al menos una orden, como say \"hello\"."),
])
def test_each_kind_of_sentence_is_whole_in_spanish(skills: SkillSchemas, text: str, expected: str) -> None:
    assert refused(text, skills).errors[0].message == expected


@pytest.mark.usefixtures("spanish")
def test_the_json_forms_errors_read_in_spanish(skills: SkillSchemas) -> None:
    invalid = json_refused({"steps": [{"kind": "if"}, {"kind": "wait"}, {"kind": "repeat"}]}, skills)
    assert [error.message for error in invalid.errors] == [
        "steps[0].condition: un paso if necesita condition, then.",
        "steps[1].duration_s: un wait necesita un duration_s, una condición o ambos.",
        "steps[2].count: un paso repeat necesita count, body.",
    ]
    assert json_refused(None, skills).errors[0].message == \
        'plan: un plan es un objeto JSON: {"format": "telelab-plan/1", "steps": [...]}.'


def test_outside_a_request_and_in_english_the_sentences_are_as_before(app: Flask, skills: SkillSchemas) -> None:
    """No app at all (a CLI), an app without a request (a run's thread) and an English request say the same English
    (the sentences the other plan tests pin, unchanged)."""
    outside = [error.message for error in refused(TWO_PROBLEMS, skills).errors]
    assert outside == [
        "line 2, column 7: goal_x_m must be between -50 and 50 m; got 120.",
        "line 3, column 5: 'max_sped' is not a setting (did you mean max_speed?); use max_speed, max_turn_rate, "
        "watchdog.",
    ]
    with app.app_context():
        assert [error.message for error in refused(TWO_PROBLEMS, skills).errors] == outside
    with app.test_request_context(), force_locale("en"):
        invalid = refused(TWO_PROBLEMS, skills)
        assert [error.message for error in invalid.errors] == outside
        assert invalid.message == outside[0] + " (and 1 more problem)"
        assert refused("go_to 1m 90deg", skills).errors[0].message == \
            "line 1, column 10: goal_y_m is a distance in m; 90deg is an angle. Use m, cm."
