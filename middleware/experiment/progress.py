"""A trial's run as it happens: whether the robot's finished run counts for the trial, and what to tell the student.

Pure functions over the robot's track run (copied from GetTrackRun by the routes) and the trial; no gRPC. The
sentences are said through gettext, in the request's language (English outside a request).
The page polls these twice a second, so arrival at A and B and every line contact show while the student drives.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime

from flask_babel import gettext, ngettext  # type: ignore[import-untyped]

from middleware.errors import written_number
from middleware.models.experiment import Trial


@dataclass(frozen=True)
class TrackRunNow:
    """The robot's track run as its track monitor reports it now."""

    phase: str  # at_start | to_b | to_a | finished
    attempt: int
    elapsed_s: float  # since the attempt started, restarts after line contacts included
    errors: int  # line contacts in this attempt
    last_attempt: int  # the last finished attempt, 0 when none
    last_total_time_s: float
    last_errors: int
    last_finished_unix_s: float
    started_unix_s: float = 0.0  # when the present attempt started (0: none)
    last_started_unix_s: float = 0.0  # when the last finished attempt started


def _unix_s(moment: datetime) -> float:
    """Seconds since the epoch; SQLite hands back naive datetimes, which are UTC here."""
    return (moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment).timestamp()


# The skill server's clock stamps the attempts; it may be another machine's, a little off.
CLOCK_SLACK_S = 1.0


def finished_in_trial(trial: Trial, run: TrackRunNow) -> bool:
    """Whether the robot finished a run that began after the trial did (that run is the trial's result).

    A run that was under way when the trial began does not count, even if it ends later: its clock started
    before the trial's condition (delay, feedback) applied.
    """
    return run.last_attempt > 0 and run.last_started_unix_s >= _unix_s(trial.created_at) - CLOCK_SLACK_S


def track_route(trial: Trial) -> str:
    """The drive the trial's track asks for: "A to B", and back on track A."""
    return str(gettext("A to B and back") if trial.course == "course-A" else gettext("A to B"))


def _sent_back_to_a(run: TrackRunNow) -> bool:
    """A line contact put the robot back at A in the middle of an attempt (its clock keeps running)."""
    return run.phase == "at_start" and run.attempt > 0 and run.last_attempt != run.attempt


def _attempt_under_way(run: TrackRunNow) -> bool:
    return run.phase in ("to_b", "to_a") or _sent_back_to_a(run)


def progress_message(trial: Trial, run: TrackRunNow) -> str:
    """One sentence for the student: where the run is and what to do next."""
    if finished_in_trial(trial, run):
        return str(ngettext("Finished in %(time)s s with %(num)d line contact.",
                            "Finished in %(time)s s with %(num)d line contacts.", run.last_errors,
                            time=written_number(run.last_total_time_s, ".1f")))
    if _attempt_under_way(run) and run.started_unix_s < _unix_s(trial.created_at) - CLOCK_SLACK_S:
        return str(gettext("This run began before your trial, so it will not count: finish it (%(route)s), return "
                           "to A (blue) and start again.", route=track_route(trial)))
    if run.phase == "to_b":
        if run.errors:
            return str(ngettext("Run %(attempt)s under way: drive to B (orange). %(num)d line contact so far.",
                                "Run %(attempt)s under way: drive to B (orange). %(num)d line contacts so far.",
                                run.errors, attempt=run.attempt))
        return str(gettext("Run %(attempt)s under way: drive to B (orange).", attempt=run.attempt))
    if run.phase == "to_a":
        return str(gettext("Reached B: now drive back to A (blue)."))
    if _sent_back_to_a(run):
        return str(gettext("The robot touched a white line and is back at A; the clock keeps running. Drive to B "
                           "again."))
    if run.phase == "finished":
        return str(gettext("The last run ended or was given up away from A: drive the robot back to A (blue) to "
                           "begin."))
    return str(gettext("The robot is at A (blue): drive off to start the clock."))


def progress_view(trial: Trial, run: TrackRunNow) -> dict[str, object]:
    """The run for the page: phase (the robot's, or return_to_a while it must go back to A), the time and line
    contacts that matter now, finished or not, the sentence."""
    finished = finished_in_trial(trial, run)
    return {
        "online": True,
        # The robot's "finished" that is not the trial's run (an earlier or given-up one) must not look like success.
        "phase": "finished" if finished else ("return_to_a" if run.phase == "finished" else run.phase),
        "attempt": run.last_attempt if finished else run.attempt,
        "time_s": round(run.last_total_time_s if finished else run.elapsed_s, 1),
        "errors": run.last_errors if finished else run.errors,
        "finished": finished,
        "message": progress_message(trial, run),
    }
