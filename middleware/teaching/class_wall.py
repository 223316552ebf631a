"""The class wall's rules: raised hands, a tutor's takeover of a student's robot, notes, pointers and pushes.

Everything here is in the database (middleware/models/class_wall.py), so every worker shows the same wall; each
change is announced on the event bus (topic "class-wall", the class session's id), which wakes the wall and the
students' class pages in every worker at once (class_wall_live.py). A takeover holds while the tutor's wall is
open: the wall refreshes it every few seconds, and one not heard of for TAKEOVER_FRESH_S has ended, so a tutor who
leaves (a closed tab, a dead worker) gives the robot back by themselves. The command path asks `WallOversight`
(handed to it by create_app) who may reach a student's robot and who holds it now.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta

from flask_babel import gettext, lazy_gettext  # type: ignore[import-untyped]
from sqlalchemy import select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session, sessionmaker

from middleware import events
from middleware.courses.services import managed_course
from middleware.errors import Refused
from middleware.i18n import N_
from middleware.models import Course, Lesson, StoredPlan, User
from middleware.models.accounts import utc_now
from middleware.models.assessment import Attempt, Exam
from middleware.models.class_wall import ClassHand, ClassNotice, ClassTakeover
from middleware.models.exercises import Exercise
from middleware.models.farm import ClassSeat, ClassSession, PersonalRobotRecord
from middleware.teaching import class_sessions
from middleware.teaching.practice_robots import practice_name
from middleware.validation import MAX_ROW_ID

TOPIC = "class-wall"
TAKEOVER_FRESH_S = 12.0  # a takeover whose wall was not heard of for this long has ended (the tutor left)
TAKEOVER_REFRESH_S = 4.0  # how often an open wall says its tutor is still there
HELD_CACHE_S = 1.0  # how long a process keeps a holder, or "nobody" while it may miss an announcement
HELD_HEARD_S = 15.0  # "nobody holds it" while it hears them: a takeover's announcement drops it at once
OVERSEES_CACHE_S = 5.0
HAND_TEXT_MAX = 200
NOTE_TEXT_MAX = 300
NOTICES_SHOWN = 10
PUSH_KINDS = {"lesson": "a lesson", "plan": "a plan", "test": "a test", "exercise": "an exercise"}
# The refusal of a push whose item is not there, said per kind (each language words a kind its own way).
_NOT_SENDABLE = {"lesson": N_("There is no lesson %(id)s you can send to this class."),
                 "plan": N_("There is no plan %(id)s you can send to this class."),
                 "test": N_("There is no test %(id)s you can send to this class."),
                 "exercise": N_("There is no exercise %(id)s you can send to this class.")}


def announce(session: Session, class_session_id: int) -> None:
    """Announces a change of the class's wall, heard by every worker once session commits."""
    events.announce(session, TOPIC, str(class_session_id))


def _fresh_after() -> datetime:
    return datetime.now(UTC) - timedelta(seconds=TAKEOVER_FRESH_S)


def wall_session(session: Session, actor: User, course_id: int) -> tuple[Course, ClassSession]:
    """The course's open class session, for its tutors and admins (404, 403; 409 when none is open)."""
    course = managed_course(session, actor, course_id)
    opened = class_sessions.open_session(session, course.id)
    if opened is None:
        raise Refused(409, "no_class_session", gettext("No class session is open for this course; start one first."))
    return course, opened


def _seat(session: Session, opened: ClassSession, user_id: int) -> tuple[ClassSeat, str]:
    row = session.execute(select(ClassSeat, User.username).join(User, User.id == ClassSeat.user_id).where(
        ClassSeat.session_id == opened.id, ClassSeat.user_id == user_id)).first()
    if row is None:
        raise Refused(404, "unknown_seat", gettext("That student has no seat in this class session."), "user_id")
    return row[0], row[1]


def seat_robot(session: Session, actor: User, course_id: int, user_id: int) -> tuple[ClassSession, str]:
    """The class session and the robot of user_id's seat, for the course's tutors (404 naming user_id)."""
    _course, opened = wall_session(session, actor, course_id)
    seat, username = _seat(session, opened, user_id)
    return opened, practice_name(username, seat.user_id)


def class_robots(session: Session, opened: ClassSession) -> list[tuple[int, str]]:
    """(student id, robot name) of every seat of the session."""
    rows = session.execute(select(ClassSeat.user_id, User.username).join(User, User.id == ClassSeat.user_id)
                           .where(ClassSeat.session_id == opened.id).order_by(User.username)).all()
    return [(user_id, practice_name(username, user_id)) for user_id, username in rows]


@dataclass(frozen=True)
class WallSeat:
    """One tile of the wall: the student, their robot, its seat's state, their hand, the tutor holding it."""

    user_id: int
    username: str
    robot: str
    seat_state: str
    message: str
    hand: dict[str, object] | None
    held_by: str | None
    testing: bool

    def to_dict(self) -> dict[str, object]:
        """The JSON form."""
        return {"user_id": self.user_id, "username": self.username, "robot": self.robot,
                "seat_state": self.seat_state, "message": self.message, "hand": self.hand,
                "held_by": self.held_by, "testing": self.testing}


def wall_seats(session: Session, class_session_id: int) -> list[WallSeat]:
    """Every seat of the session as the wall shows it, in a few reads whatever the class's size."""
    rows = session.execute(select(ClassSeat, User.username).join(User, User.id == ClassSeat.user_id)
                           .where(ClassSeat.session_id == class_session_id).order_by(User.username)).all()
    running = set(session.scalars(select(PersonalRobotRecord.owner_id).where(
        PersonalRobotRecord.class_session_id == class_session_id, PersonalRobotRecord.address != "")))
    hands = {hand.user_id: hand for hand in session.scalars(select(ClassHand).where(
        ClassHand.session_id == class_session_id, ClassHand.answered_at.is_(None)))}
    held = dict(session.execute(select(ClassTakeover.user_id, User.username)
                                .join(User, User.id == ClassTakeover.tutor_id)
                                .where(ClassTakeover.session_id == class_session_id,
                                       ClassTakeover.ended_at.is_(None),
                                       ClassTakeover.heard_at > _fresh_after())).all())
    user_ids = [seat.user_id for seat, _name in rows]
    testing = set(session.scalars(select(Attempt.user_id).where(
        Attempt.user_id.in_(user_ids), Attempt.status == "in_progress"))) if user_ids else set()
    seats = []
    for seat, username in rows:
        state = class_sessions.live_state(seat.state, seat.user_id in running)
        hand = hands.get(seat.user_id)
        message = (gettext(class_sessions.STOPPED_WHILE_OPEN) if state != seat.state
                   else class_sessions.seat_message(seat.message))
        seats.append(WallSeat(
            seat.user_id, username, practice_name(username, seat.user_id), state, message,
            None if hand is None else {"text": hand.text, "raised_at": _iso(hand.raised_at)},
            held.get(seat.user_id), seat.user_id in testing))
    return seats


def _iso(moment: datetime) -> str:
    stamp = moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment
    return stamp.astimezone(UTC).isoformat().replace("+00:00", "Z")


def clean_text(value: object, field: str, limit: int, required: bool = False) -> str:
    """A sentence a person typed: a string of at most limit characters (stripped), or a 400 naming field."""
    if value is None:
        value = ""
    if not isinstance(value, str):
        raise Refused(400, "invalid_field", gettext("%(field)s must be text.", field=field), field)
    text = " ".join(value.split())
    if len(text) > limit:
        raise Refused(400, "invalid_field", gettext("%(field)s is %(length)s characters long; at most %(limit)s fit.",
                                                    field=field, length=len(text), limit=limit), field)
    if required and not text:
        raise Refused(400, "invalid_field", gettext("%(field)s is empty: write a sentence first.", field=field), field)
    return text


def _my_open_seat(session: Session, actor: User) -> ClassSeat:
    found = class_sessions.my_seat(session, actor)
    if found is None:
        raise Refused(409, "no_class_session", gettext("No class session is open for your courses now."))
    return found[1]


def raise_hand(session: Session, actor: User, text: object) -> ClassHand:
    """Raises the student's hand in their open class (the sentence replaces the one of a hand already up)."""
    seat = _my_open_seat(session, actor)
    sentence = clean_text(text, "text", HAND_TEXT_MAX)
    hand = session.scalar(select(ClassHand).where(ClassHand.session_id == seat.session_id,
                                                  ClassHand.user_id == actor.id, ClassHand.answered_at.is_(None)))
    if hand is None:
        hand = ClassHand(session_id=seat.session_id, user_id=actor.id, text=sentence)
        session.add(hand)
    else:
        hand.text, hand.raised_at = sentence, utc_now()
    try:
        session.flush()
    except IntegrityError:  # the same student raised it twice at once in two workers; the owner rolls back
        raise Refused(409, "hand_raised", lazy_gettext("Your hand is up already.")) from None
    announce(session, seat.session_id)
    return hand


def lower_hand(session: Session, actor: User) -> None:
    """The student lowers their own hand (nothing happens when it is down)."""
    seat = _my_open_seat(session, actor)
    _answer(session, seat.session_id, actor.id, actor.id)


def answer_hand(session: Session, actor: User, course_id: int, user_id: int) -> None:
    """The tutor answered the student's hand: it comes down on the wall and on the student's page."""
    _course, opened = wall_session(session, actor, course_id)
    _seat(session, opened, user_id)
    _answer(session, opened.id, user_id, actor.id)


def _answer(session: Session, class_session_id: int, user_id: int, by_id: int) -> None:
    session.execute(update(ClassHand).where(ClassHand.session_id == class_session_id, ClassHand.user_id == user_id,
                                            ClassHand.answered_at.is_(None))
                    .values(answered_at=utc_now(), answered_by_id=by_id))
    announce(session, class_session_id)


def take_over(session: Session, actor: User, course_id: int, user_id: int) -> str:
    """The tutor holds the student's robot (the student's commands are refused until it ends); the robot's name.
    Another tutor's live takeover of it is a 409."""
    opened, robot = seat_robot(session, actor, course_id, user_id)
    holder = session.scalar(select(ClassTakeover.tutor_id).where(
        ClassTakeover.robot_name == robot, ClassTakeover.ended_at.is_(None), ClassTakeover.heard_at > _fresh_after()))
    if holder is not None and holder != actor.id:
        raise Refused(409, "taken_over", gettext("Another tutor holds this robot now."), "user_id")
    session.execute(update(ClassTakeover).where(ClassTakeover.robot_name == robot, ClassTakeover.ended_at.is_(None))
                    .values(ended_at=utc_now()))
    session.add(ClassTakeover(session_id=opened.id, user_id=user_id, tutor_id=actor.id, robot_name=robot))
    try:
        session.flush()
    except IntegrityError:
        raise Refused(409, "taken_over", lazy_gettext("Another tutor took this robot over at the same moment."),
                      "user_id") from None
    announce(session, opened.id)
    return robot


def give_back(session: Session, actor: User, course_id: int, user_id: int) -> None:
    """The robot goes back to its student (whichever tutor held it)."""
    opened, robot = seat_robot(session, actor, course_id, user_id)
    session.execute(update(ClassTakeover).where(ClassTakeover.robot_name == robot, ClassTakeover.ended_at.is_(None))
                    .values(ended_at=utc_now()))
    announce(session, opened.id)


def still_watching(session: Session, class_session_id: int, tutor_id: int) -> None:
    """The tutor's wall is open: their takeovers in the session hold on."""
    session.execute(update(ClassTakeover).where(ClassTakeover.session_id == class_session_id,
                                                ClassTakeover.tutor_id == tutor_id, ClassTakeover.ended_at.is_(None))
                    .values(heard_at=utc_now()))


def tutor_left(session: Session, class_session_id: int, tutor_id: int) -> None:
    """The tutor closed the wall: every robot they held goes back to its student at once."""
    ended = session.execute(update(ClassTakeover).where(
        ClassTakeover.session_id == class_session_id, ClassTakeover.tutor_id == tutor_id,
        ClassTakeover.ended_at.is_(None)).values(ended_at=utc_now()))
    if getattr(ended, "rowcount", 0):
        announce(session, class_session_id)


def send_note(session: Session, actor: User, course_id: int, user_id: int, text: object,
              point: object = None) -> ClassNotice:
    """A note (and, with point, a pointer on the student's map) from the tutor to one student."""
    opened, _robot = seat_robot(session, actor, course_id, user_id)
    sentence = clean_text(text, "text", NOTE_TEXT_MAX, required=point is None)
    body: dict[str, object] = {"text": sentence}
    kind = "note"
    if point is not None:
        body["x_m"], body["y_m"] = _point(point)
        kind = "pointer"
    notice = ClassNotice(session_id=opened.id, user_id=user_id, from_id=actor.id, kind=kind, body=body)
    session.add(notice)
    session.flush()
    announce(session, opened.id)
    return notice


def _point(value: object) -> tuple[float, float]:
    if not isinstance(value, dict):
        raise Refused(400, "invalid_field", gettext("point must be an object with x_m and y_m in metres."), "point")
    coordinates = []
    for name in ("x_m", "y_m"):
        number = value.get(name)
        if isinstance(number, bool) or not isinstance(number, int | float) or not -50 <= number <= 50:
            raise Refused(400, "invalid_field", gettext("point.%(name)s must be a number of metres from -50 to 50.",
                                                        name=name), f"point.{name}")
        coordinates.append(round(float(number), 3))
    return coordinates[0], coordinates[1]


def push(session: Session, actor: User, course_id: int, kind: object, item_id: object) -> ClassNotice:
    """Sends every student of the class a lesson, an exercise, a plan shared with the course or a test of the
    course."""
    course, opened = wall_session(session, actor, course_id)
    if not isinstance(kind, str) or kind not in PUSH_KINDS:
        raise Refused(400, "invalid_field", gettext("kind must be one of %(kinds)s.", kinds=", ".join(PUSH_KINDS)),
                      "kind")
    if isinstance(item_id, bool) or not isinstance(item_id, int) or not 1 <= item_id <= MAX_ROW_ID:
        raise Refused(400, "invalid_field", gettext("id must be the number of what you send."), "id")
    title, url = _pushed(session, course, kind, item_id)
    notice = ClassNotice(session_id=opened.id, user_id=None, from_id=actor.id, kind="push",
                         body={"what": kind, "id": item_id, "title": title, "url": url})
    session.add(notice)
    session.flush()
    announce(session, opened.id)
    return notice


def _pushed(session: Session, course: Course, kind: str, item_id: int) -> tuple[str, str]:
    if kind == "lesson":
        lesson = session.get(Lesson, item_id)
        if lesson is not None:
            return lesson.title, f"/lessons/{lesson.id}"
    elif kind == "plan":
        plan = session.get(StoredPlan, item_id)
        if plan is not None and plan.shared_course_id == course.id:
            return plan.name, f"/plans/{plan.id}"
        if plan is not None:
            raise Refused(400, "invalid_field", gettext("Share the plan with the course first: its students cannot "
                                                        "open it otherwise."), "id")
    elif kind == "exercise":
        exercise = session.get(Exercise, item_id)
        if exercise is not None:
            return exercise.title, f"/exercises/{exercise.slug}"
    else:
        exam = session.get(Exam, item_id)
        if exam is not None and exam.course_id == course.id:
            return exam.title, f"/assessment/exams/{exam.id}"
    raise Refused(400, "invalid_field", gettext(_NOT_SENDABLE[kind], id=item_id), "id")


def choices(session: Session, course: Course) -> dict[str, list[dict[str, object]]]:
    """What the wall's push menu offers: every lesson and exercise, the plans shared with the course, the course's
    tests."""
    lessons = session.execute(select(Lesson.id, Lesson.title).order_by(Lesson.title)).all()
    plans = session.execute(select(StoredPlan.id, StoredPlan.name).where(StoredPlan.shared_course_id == course.id)
                            .order_by(StoredPlan.name)).all()
    exams = session.execute(select(Exam.id, Exam.title).where(Exam.course_id == course.id)
                            .order_by(Exam.title)).all()
    exercises = session.execute(select(Exercise.id, Exercise.title).order_by(Exercise.title)).all()
    return {kind: [{"id": row[0], "title": row[1]} for row in rows]
            for kind, rows in (("lesson", lessons), ("exercise", exercises), ("plan", plans), ("test", exams))}


def student_view(session: Session, actor: User) -> dict[str, object]:
    """What the student's class page shows of the wall: their hand, who holds their robot, the tutor's notices."""
    found = class_sessions.my_seat(session, actor)
    if found is None:
        return {"open": False}
    course, seat = found
    hand = session.scalar(select(ClassHand).where(ClassHand.session_id == seat.session_id,
                                                  ClassHand.user_id == actor.id, ClassHand.answered_at.is_(None)))
    holder = session.scalar(select(User.username).join(ClassTakeover, ClassTakeover.tutor_id == User.id).where(
        ClassTakeover.session_id == seat.session_id, ClassTakeover.user_id == actor.id,
        ClassTakeover.ended_at.is_(None), ClassTakeover.heard_at > _fresh_after()))
    notices = session.execute(select(ClassNotice, User.username).outerjoin(User, User.id == ClassNotice.from_id)
                              .where(ClassNotice.session_id == seat.session_id,
                                     (ClassNotice.user_id == actor.id) | ClassNotice.user_id.is_(None))
                              .order_by(ClassNotice.id.desc()).limit(NOTICES_SHOWN)).all()
    return {"open": True, "session_id": seat.session_id, "course_id": course.id,
            "robot": practice_name(actor.username, actor.id),
            "hand": None if hand is None else {"text": hand.text, "raised_at": _iso(hand.raised_at)},
            "held_by": holder,
            "notices": [{"id": notice.id, "kind": notice.kind, "from": name, "at": _iso(notice.created_at),
                         **notice.body} for notice, name in notices]}


class WallOversight:
    """The command path's `Oversight`: a class's tutors (and admins) reach its students' robots, and a live
    takeover gives its tutor the robot. Answers are kept per process (events.KeptAnswers) and dropped when the wall's
    topic is announced, as every takeover's start and end is, so a student's 20 commands a second cost no read each:
    "nobody holds it" is kept while this process hears the announcements, a holder HELD_CACHE_S (a takeover whose
    tutor went quiet ends unannounced)."""

    def __init__(self, sessions: sessionmaker[Session]) -> None:
        self._sessions = sessions
        engine = sessions.kw["bind"]
        self._held: events.KeptAnswers[str, int | None] = events.KeptAnswers(
            engine, TOPIC, HELD_CACHE_S, HELD_HEARD_S, keyed=False)
        self._oversees: events.KeptAnswers[tuple[str, int], bool] = events.KeptAnswers(
            engine, TOPIC, OVERSEES_CACHE_S, OVERSEES_CACHE_S, keyed=False)

    def held_by(self, robot_name: str) -> int | None:
        """The tutor holding robot_name now, or None."""
        return self._held.get(robot_name, lambda: self._read_holder(robot_name),
                              lambda holder: math.inf if holder is None else HELD_CACHE_S)

    def _read_holder(self, robot_name: str) -> int | None:
        with self._sessions() as session:
            return session.scalar(select(ClassTakeover.tutor_id).where(
                ClassTakeover.robot_name == robot_name, ClassTakeover.ended_at.is_(None),
                ClassTakeover.heard_at > _fresh_after()))

    def remembered_holder(self, robot_name: str) -> tuple[bool, int | None]:
        """(True, the tutor holding robot_name or None) when this process's answer is fresh, else (False, None)."""
        return self._held.known(robot_name)

    def oversees(self, robot_name: str, user_id: int) -> bool:
        """Whether user_id teaches the course of the open class session robot_name was started for."""
        return self._oversees.get((robot_name, user_id), lambda: self._read_oversees(robot_name, user_id))

    def _read_oversees(self, robot_name: str, user_id: int) -> bool:
        with self._sessions() as session:
            course_id = session.scalar(select(ClassSession.course_id).join(
                PersonalRobotRecord, PersonalRobotRecord.class_session_id == ClassSession.id).where(
                PersonalRobotRecord.name == robot_name, ClassSession.ended_at.is_(None)))
            actor = session.get(User, user_id)
            if course_id is None or actor is None or not actor.is_active:
                return False
            try:
                managed_course(session, actor, course_id)
            except Refused:
                return False
            return True
