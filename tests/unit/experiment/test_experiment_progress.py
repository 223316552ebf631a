"""A trial's run as the page shows it while the student drives: which run counts, and the sentence for each phase."""

from __future__ import annotations

from datetime import UTC, datetime

import pytest

from middleware.experiment.progress import (
    TrackRunNow,
    finished_in_trial,
    progress_message,
    progress_view,
    track_route,
)
from middleware.models.experiment import Trial

BEGAN = datetime(2025, 3, 1, 10, 0, 0, tzinfo=UTC)


def trial(course: str = "course-B", created_at: datetime = BEGAN) -> Trial:
    return Trial(id=1, user_id=1, robot_name="course-b", course=course, delay_s=1.0, feedback=True,
                 status="assigned", errors=0, created_at=created_at)


def run(phase: str, attempt: int = 1, errors: int = 0, last_attempt: int = 0, finished_at: datetime | None = None,
        elapsed_s: float = 4.0, started_at: datetime | None = None) -> TrackRunNow:
    """A run; the last finished attempt took 12.34 s, the present one started a minute into the trial."""
    finished = finished_at.timestamp() if finished_at else 0.0
    started = (started_at or BEGAN).timestamp() + (0 if started_at else 60)
    return TrackRunNow(phase, attempt, elapsed_s, errors, last_attempt, 12.34 if last_attempt else 0.0,
                        2 if last_attempt else 0, finished, started if attempt else 0.0,
                        finished - 12.34 if last_attempt else 0.0)


# Each moment of a run: (the run now, its sentence in English, in Spanish).
SENTENCES = [
    (run("at_start", attempt=0), "The robot is at A (blue): drive off to start the clock.",
     "El robot está en A (azul): arranca para poner en marcha el reloj."),
    (run("to_b"), "Run 1 under way: drive to B (orange).", "Recorrido 1 en curso: conduce hasta B (naranja)."),
    (run("to_b", errors=1), "Run 1 under way: drive to B (orange). 1 line contact so far.",
     "Recorrido 1 en curso: conduce hasta B (naranja). 1 roce con una línea hasta ahora."),
    (run("to_b", errors=2), "Run 1 under way: drive to B (orange). 2 line contacts so far.",
     "Recorrido 1 en curso: conduce hasta B (naranja). 2 roces con las líneas hasta ahora."),
    (run("to_a"), "Reached B: now drive back to A (blue).", "Has llegado a B: ahora vuelve a A (azul)."),
    (run("at_start", errors=1), "The robot touched a white line and is back at A; the clock keeps running. "
                                "Drive to B again.",
     "El robot tocó una línea blanca y ha vuelto a A; el reloj sigue corriendo. Conduce de nuevo hasta B."),
    (run("finished", last_attempt=1, finished_at=datetime(2025, 3, 1, 9, 0, tzinfo=UTC)),
     "The last run ended or was given up away from A: drive the robot back to A (blue) to begin.",
     "El último recorrido terminó o se abandonó lejos de A: lleva el robot de vuelta a A (azul) para empezar."),
    (run("at_start", attempt=1, last_attempt=1, finished_at=datetime(2025, 3, 1, 9, 0, tzinfo=UTC)),
     "The robot is at A (blue): drive off to start the clock.",
     "El robot está en A (azul): arranca para poner en marcha el reloj."),
    (run("at_start", attempt=2, last_attempt=2, finished_at=datetime(2025, 3, 1, 10, 5, tzinfo=UTC)),
     "Finished in 12.3 s with 2 line contacts.", "Terminado en 12,3 s con 2 roces con las líneas."),
    (run("to_b", started_at=datetime(2025, 3, 1, 9, 59, 40, tzinfo=UTC)),
     "This run began before your trial, so it will not count: finish it (A to B), return to A (blue) and start "
     "again.",
     "Este recorrido empezó antes de tu ensayo, así que no cuenta: termínalo (A a B), vuelve a A (azul) y empieza de "
     "nuevo."),
]


@pytest.mark.parametrize(("now", "sentence"), [(now, english) for now, english, _ in SENTENCES])
def test_each_moment_of_a_run_has_its_sentence(now: TrackRunNow, sentence: str) -> None:
    assert progress_message(trial(), now) == sentence


def test_only_a_run_finished_after_the_trial_began_counts_even_from_a_naive_sqlite_time() -> None:
    naive = trial(created_at=BEGAN.replace(tzinfo=None))
    before = run("finished", last_attempt=1, finished_at=datetime(2025, 3, 1, 9, 59, 59, tzinfo=UTC))
    after = run("at_start", attempt=1, last_attempt=1, finished_at=datetime(2025, 3, 1, 10, 0, 13, tzinfo=UTC))
    assert not finished_in_trial(naive, before) and finished_in_trial(naive, after)
    assert not finished_in_trial(naive, run("to_b"))


def test_a_run_under_way_when_the_trial_began_does_not_count_even_if_it_ends_after() -> None:
    # 12.34 s long, finished 5 s into the trial: it began 7 s before the trial.
    straddling = run("at_start", attempt=1, last_attempt=1, finished_at=datetime(2025, 3, 1, 10, 0, 5, tzinfo=UTC))
    assert not finished_in_trial(trial(), straddling)
    early = run("to_b", started_at=datetime(2025, 3, 1, 9, 59, 40, tzinfo=UTC))
    assert progress_message(trial(), early) == (
        "This run began before your trial, so it will not count: finish it (A to B), return to A (blue) and "
        "start again.")
    assert progress_message(trial(), run("to_b")) == "Run 1 under way: drive to B (orange)."

def test_the_view_shows_the_finished_run_s_time_and_contacts_once_it_counts() -> None:
    live = progress_view(trial(), run("to_b", errors=1, elapsed_s=7.26))
    assert live == {"online": True, "phase": "to_b", "attempt": 1, "time_s": 7.3, "errors": 1, "finished": False,
                    "message": "Run 1 under way: drive to B (orange). 1 line contact so far."}
    done = progress_view(trial(), run("at_start", attempt=3, last_attempt=3,
                                      finished_at=datetime(2025, 3, 1, 10, 1, tzinfo=UTC)))
    assert done["finished"] and done["phase"] == "finished" and (done["time_s"], done["errors"]) == (12.3, 2)


def test_a_robot_that_must_go_back_to_a_is_not_shown_as_finished() -> None:
    earlier = progress_view(trial(), run("finished", last_attempt=1,
                                         finished_at=datetime(2025, 3, 1, 9, 0, tzinfo=UTC)))
    assert earlier["phase"] == "return_to_a" and not earlier["finished"]


@pytest.mark.parametrize(("now", "sentence"), [(now, spanish) for now, _, spanish in SENTENCES])
def test_a_spanish_student_reads_each_moment_of_a_run_in_spanish(now: TrackRunNow, sentence: str) -> None:
    from flask import Flask
    from flask_babel import Babel, force_locale  # type: ignore[import-untyped]

    from middleware.translations.build import TRANSLATIONS

    app = Flask(__name__)
    Babel(app, default_translation_directories=str(TRANSLATIONS))  # the lab's real catalogues
    with app.test_request_context(), force_locale("es"):
        assert progress_message(trial(), now) == sentence
        assert track_route(trial("course-A")) == "A a B y de vuelta"
