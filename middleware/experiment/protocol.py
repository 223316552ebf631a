"""The thesis' protocol around the trials: the conditions (a no-delay control beside the 1 s and 3 s delays, the
preview on and off), the order each student runs them in (counterbalanced), the participant's details (asked once,
kept only with consent), the learning period before the first trial, and what a course's tutor sets.

Services take the session and the acting user, never read flask.request, and leave committing to the caller.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timedelta

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import func, select, text
from sqlalchemy.orm import Session

from middleware.courses.authority import teaches_course
from middleware.errors import Refused
from middleware.locking import lock_user
from middleware.models import Course, Role, User
from middleware.models.accounts import utc_now
from middleware.models.experiment import ExperimentProtocol, Participant, Trial

CONTROL_DELAY_S = 0.0
# Per course: the no-delay control (the preview has nothing to predict without a delay, so it is off), then each
# delay with the preview on and off.
CONDITIONS_PER_COURSE: tuple[tuple[float, bool], ...] = (
    (CONTROL_DELAY_S, False), (1.0, True), (1.0, False), (3.0, True), (3.0, False))
DEFAULT_LEARNING_S = 300
MAX_LEARNING_S = 3600
EXPERIENCE = ("none", "some", "much")
LOCATIONS = ("lab", "remote")
ORDER_LOCKS = 0x3E7E_0DE5  # the namespace of the advisory locks that hand out a course's orders one at a time


def williams_orders(n: int) -> list[list[int]]:
    """A Williams design over n conditions: every condition comes first, and follows every other, equally often
    (n rows for an even n, 2n for an odd one: the rows and their mirrors), so order and carry-over effects cancel
    over the class."""
    first, low, high = [0], 1, n - 1
    while len(first) < n:
        first.append(low)
        low += 1
        if len(first) < n:
            first.append(high)
            high -= 1
    rows = [[(c + shift) % n for c in first] for shift in range(n)]
    return rows if n % 2 == 0 else rows + [list(reversed(row)) for row in rows]


ORDERS = williams_orders(len(CONDITIONS_PER_COURSE))


@dataclass(frozen=True)
class Protocol:
    """What applies to a student's trials: their class course's settings, or the defaults."""

    learning_s: int = DEFAULT_LEARNING_S
    delay_commands: bool = False
    export_participants: bool = False


def protocol_for(session: Session, course_id: int | None) -> Protocol:
    row = session.get(ExperimentProtocol, course_id) if course_id is not None else None
    if row is None:
        return Protocol()
    return Protocol(row.learning_s, row.delay_commands, row.export_participants)


def _flag(body: dict[str, object], field: str, current: bool) -> bool:
    value = body.get(field, current)
    if not isinstance(value, bool):
        raise Refused(400, "invalid_field", gettext("%(field)s must be true or false.", field=field), field)
    return value


def set_protocol(session: Session, actor: User, course_id: int, body: dict[str, object]) -> Protocol:
    """A tutor of the course (or an admin) sets its learning period (0-3600 s) and the two switches."""
    course = session.get(Course, course_id)
    if course is None:
        raise Refused(404, "unknown_course", gettext("There is no such course."), "course_id")
    if actor.role != Role.ADMIN and not teaches_course(session, actor, course.id):
        raise Refused(403, "forbidden", gettext("Only the course's tutors set its experiment protocol."), "course_id")
    current = protocol_for(session, course.id)
    learning = body.get("learning_s", current.learning_s)
    if isinstance(learning, bool) or not isinstance(learning, int | float) or not math.isfinite(learning) \
            or not 0 <= learning <= MAX_LEARNING_S:
        raise Refused(400, "invalid_field", gettext("learning_s must be from 0 to %(high)s seconds.",
                                                    high=MAX_LEARNING_S), "learning_s")
    settings = Protocol(int(learning), _flag(body, "delay_commands", current.delay_commands),
                        _flag(body, "export_participants", current.export_participants))
    row = session.get(ExperimentProtocol, course.id)
    if row is None:
        row = ExperimentProtocol(course_id=course.id)
        session.add(row)
    row.learning_s, row.delay_commands = settings.learning_s, settings.delay_commands
    row.export_participants, row.updated_at = settings.export_participants, utc_now()
    session.flush()
    return settings


def participant(session: Session, user_id: int) -> Participant | None:
    return session.get(Participant, user_id)


def _participant_row(session: Session, user_id: int) -> Participant:
    row = session.get(Participant, user_id)
    if row is None:
        row = Participant(user_id=user_id, consent=False)
        session.add(row)
        session.flush()
    return row


def _choice(body: dict[str, object], field: str, allowed: tuple[str, ...]) -> str | None:
    value = body.get(field)
    if value is None or value == "":
        return None
    if value not in allowed:
        raise Refused(400, "invalid_field", gettext("%(field)s must be one of %(allowed)s.", field=field,
                                                    allowed=", ".join(allowed)), field)
    return str(value)


def answer_details(session: Session, student: User, body: dict[str, object]) -> Participant:
    """The student's details, asked once: kept only when they consent (then every field is checked and may be
    left empty); without consent nothing but the refusal is kept, and they are not asked again."""
    consent = body.get("consent")
    if not isinstance(consent, bool):
        raise Refused(400, "invalid_field", gettext("Say whether you agree to your details being kept (consent)."),
                      "consent")
    row = _participant_row(session, student.id)
    row.consent, row.answered_at = consent, utc_now()
    row.age = row.location = row.games_experience = row.robots_experience = None
    if consent:
        age = body.get("age")
        if age not in (None, ""):
            if isinstance(age, bool) or not isinstance(age, int) or not 10 <= age <= 120:
                raise Refused(400, "invalid_field", gettext("age must be a whole number of years from 10 to 120."),
                              "age")
            row.age = age
        row.location = _choice(body, "location", LOCATIONS)
        row.games_experience = _choice(body, "games_experience", EXPERIENCE)
        row.robots_experience = _choice(body, "robots_experience", EXPERIENCE)
    session.flush()
    return row


def start_learning(session: Session, student: User) -> Participant:
    """Starts the student's learning period (once: starting again keeps the first start)."""
    row = _participant_row(session, student.id)
    if row.learning_started_at is None:
        row.learning_started_at = utc_now()
        session.flush()
    return row


def learning_left_s(row: Participant | None, protocol: Protocol, now: datetime) -> float | None:
    """Seconds of the learning period still to go: None when it has not started, 0 once it is over (or none is set)."""
    if protocol.learning_s == 0:
        return 0.0
    if row is None or row.learning_started_at is None:
        return None
    started = row.learning_started_at
    if started.tzinfo is None:  # SQLite gives naive UTC back
        started = started.replace(tzinfo=now.tzinfo)
    return max(0.0, (started + timedelta(seconds=protocol.learning_s) - now).total_seconds())


def require_ready(session: Session, student: User, protocol: Protocol) -> None:
    """A trial begins only once the student has answered the details question and their learning period is over."""
    row = participant(session, student.id)
    if row is None or row.answered_at is None:
        raise Refused(409, "details_missing", gettext("Answer the participant questions (or decline them) before "
                                                     "your first trial."), "consent")
    left = learning_left_s(row, protocol, utc_now())
    if left is None:
        raise Refused(409, "learning_not_started", gettext(
            "Start your learning period first: %(minutes)s min to drive the course freely before the trials.",
            minutes=protocol.learning_s // 60), "learning")
    if left > 0:
        raise Refused(409, "learning_period", gettext("Your learning period ends in %(seconds)s s: drive the course "
                                                     "freely until then.", seconds=math.ceil(left)), "learning")


def _lock_orders(session: Session, student: User, course_id: int | None) -> None:
    """One order handed out at a time per course: the count below then never misses one being handed out (with
    SQLite, the user's row written first takes the database's one write lock; PostgreSQL, an advisory lock)."""
    lock_user(session, student.id)
    if session.get_bind().dialect.name == "postgresql":
        session.execute(text("SELECT pg_advisory_xact_lock(:space, :course)"),
                        {"space": ORDER_LOCKS, "course": course_id or 0})


def order_of(session: Session, student: User, course_id: int | None) -> list[tuple[float, bool]]:
    """The student's order of conditions, fixed at their first trial: the next row of the course's Williams design
    (the class's rows then differ in use by one at most)."""
    row = _participant_row(session, student.id)
    if row.order_index is None:
        _lock_orders(session, student, course_id)
        session.refresh(row)
    if row.order_index is None:
        given = session.scalar(select(func.count()).select_from(Participant).where(
            Participant.order_index.is_not(None),
            Participant.order_course_id.is_(None) if course_id is None else Participant.order_course_id == course_id))
        row.order_course_id, row.order_index = course_id, int(given or 0) % len(ORDERS)
        session.flush()
    return [CONDITIONS_PER_COURSE[i] for i in ORDERS[row.order_index % len(ORDERS)]]


def next_condition(session: Session, student: User, course_id: int | None, scene: str) -> tuple[float, bool]:
    """The next condition of the student's order on this course scene: the first one they have not completed
    (a trial given up is run again in the same condition); after the whole order, it starts over."""
    order = order_of(session, student, course_id)
    done = list(session.execute(select(Trial.delay_s, Trial.feedback).where(
        Trial.user_id == student.id, Trial.course == scene, Trial.status == "completed")))
    counts: dict[tuple[float, bool], int] = {}
    for delay, feedback in done:
        counts[(float(delay), bool(feedback))] = counts.get((float(delay), bool(feedback)), 0) + 1
    rounds = min(counts.get(c, 0) for c in order)
    return next(c for c in order if counts.get(c, 0) == rounds)


def state_for(session: Session, student: User, course_id: int | None) -> dict[str, object]:
    """What the page shows before a trial: whether the details were answered, and the learning period."""
    row = participant(session, student.id)
    protocol = protocol_for(session, course_id)
    left = learning_left_s(row, protocol, utc_now())
    return {"details_answered": row is not None and row.answered_at is not None,
            "consent": bool(row and row.consent),
            "learning_s": protocol.learning_s, "learning_left_s": left,
            "learning_started": left is not None, "learning_done": left == 0,
            "commands_delayed": protocol.delay_commands}


def participants_summary(session: Session, user_ids: set[int]) -> dict[str, object]:
    """The class's participants as the thesis' table reports them, from the consenting ones only: how many, ages,
    where they drove from and their experience with games and robots."""
    rows = list(session.scalars(select(Participant).where(Participant.user_id.in_(user_ids)))) if user_ids else []
    consenting = [r for r in rows if r.consent]
    ages = [r.age for r in consenting if r.age is not None]

    def counts(field: str, values: tuple[str, ...]) -> dict[str, int]:
        return {value: sum(1 for r in consenting if getattr(r, field) == value) for value in values}

    return {"participants": len(rows), "consenting": len(consenting),
            "age_min": min(ages) if ages else None, "age_max": max(ages) if ages else None,
            "age_mean": round(sum(ages) / len(ages), 1) if ages else None,
            "location": counts("location", LOCATIONS), "games_experience": counts("games_experience", EXPERIENCE),
            "robots_experience": counts("robots_experience", EXPERIENCE),
            "orders_in_use": _orders_in_use(rows)}


def _orders_in_use(rows: list[Participant]) -> list[int]:
    """How many of the class's participants run each row of the design (counterbalanced: within one of each other)."""
    used = [0] * len(ORDERS)
    for row in rows:
        if row.order_index is not None:
            used[row.order_index % len(ORDERS)] += 1
    return used
