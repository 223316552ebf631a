"""A trial's run as the page shows it while the student drives: which run counts, and the sentence for each phase."""

from __future__ import annotations

from datetime import UTC, datetime

import pytest

from middleware.experiment.progress import TrackRunNow, finished_in_trial, progress_message, progress_view
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


@pytest.mark.parametrize(("now", "sentence"), [
    (run("at_start", attempt=0), "The robot is at A (blue): drive off to start the clock."),
    (run("to_b"), "Run 1 under way: drive to B (orange)."),
    (run("to_b", errors=2), "Run 1 under way: drive to B (orange). 2 line contacts so far."),
    (run("to_a"), "Reached B: now drive back to A (blue)."),
    (run("at_start", errors=1), "The robot touched a white line and is back at A; the clock keeps running. "
                                "Drive to B again."),
    (run("finished", last_attempt=1, finished_at=datetime(2025, 3, 1, 9, 0, tzinfo=UTC)),
     "The last run ended or was given up away from A: drive the robot back to A (blue) to begin."),
    (run("at_start", attempt=1, last_attempt=1, finished_at=datetime(2025, 3, 1, 9, 0, tzinfo=UTC)),
     "The robot is at A (blue): drive off to start the clock."),
    (run("at_start", attempt=2, last_attempt=2, finished_at=datetime(2025, 3, 1, 10, 5, tzinfo=UTC)),
     "Finished in 12.3 s with 2 line contacts."),
])
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
