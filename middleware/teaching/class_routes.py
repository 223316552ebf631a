"""Class session pages and API: a tutor starts and ends one for a course; each student opens their robot."""

from __future__ import annotations

import time

from flask import Blueprint, current_app, jsonify, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_login import current_user, login_required
from sqlalchemy.exc import DBAPIError

from middleware.api.contract import BOOLEAN, ID, OBJECT, STRING, about, array, described, nullable, obj, whole
from middleware.courses.services import get_course
from middleware.db import after_commit, get_session, session_factory
from middleware.models import User
from middleware.teaching import class_bookings, class_sessions
from middleware.teaching.practice_robots import practice_manager, practice_name

blueprint = Blueprint("classes", __name__)
_KEEPER_KEY = "telelab.class_bookings"
LOOK_FOR_CLASS_BOOKINGS_S = 60.0


@blueprint.before_app_request
def keep_booked_classes() -> None:
    """Once a process serves requests and a class booking lies ahead, it keeps booked class sessions in step
    (the keeper itself runs in one process of the cluster)."""
    app = current_app._get_current_object()  # type: ignore[attr-defined]
    state = app.extensions.setdefault(_KEEPER_KEY, {"looked_at": -LOOK_FOR_CLASS_BOOKINGS_S, "keeper": None})
    now = time.monotonic()
    if state["keeper"] is not None or now - state["looked_at"] < LOOK_FOR_CLASS_BOOKINGS_S:
        return
    state["looked_at"] = now
    sessions = session_factory(app)
    try:
        if not class_bookings.any_class_booking_ahead(sessions):
            return
    except DBAPIError:
        return  # no tables yet
    keeper = state["keeper"] = class_bookings.ClassBookingKeeper(sessions, practice_manager(app))
    keeper.start()


def _actor() -> User:
    return get_session().get(User, int(current_user.get_id()))  # type: ignore[return-value]


SEAT = obj(("user_id", "username", "state", "message", "robot", "response_times"),
           user_id=ID, username=STRING, state=STRING, message=STRING, robot=STRING, response_times=nullable(OBJECT))
# A course's class session as its tutor sees it (_session_dict).
CLASS_SESSION = obj(("course_id", "open", "scene", "booking_id", "started_at", "seats", "counts"),
                    course_id=whole(0), open=BOOLEAN, scene=nullable(STRING), booking_id=nullable(whole()),
                    started_at=nullable(STRING), seats=array(SEAT),
                    counts=obj(("starting", "ready", "failed", "stopped"), starting=whole(0), ready=whole(0),
                               failed=whole(0), stopped=whole(0)))
# The student's own seat (_my_seat_dict): only "open" when they have none.
MY_SEAT = obj(("open",), open=BOOLEAN,
              course=obj(("id", "code", "title"), id=ID, code=STRING, title=STRING),
              state=STRING, message=STRING, robot=STRING, console_url=nullable(STRING))


def _session_dict(course_id: int) -> dict[str, object]:
    opened, seats = class_sessions.seats(get_session(), _actor(), course_id)
    states = ("starting", "ready", "failed", "stopped")
    counts = {state: sum(1 for seat in seats if seat.state == state) for state in states}
    return {"course_id": course_id, "open": opened is not None, "scene": opened.scene if opened else None,
            "booking_id": opened.booking_id if opened else None,
            "started_at": opened.started_at.isoformat() if opened else None,
            "seats": [seat.to_dict() for seat in seats], "counts": counts}


@blueprint.get("/courses/<int:course_id>/class")
@login_required
def tutor_page(course_id: int) -> ResponseReturnValue:
    """The tutor's class session page: start, everyone's robot, end."""
    class_sessions.seats(get_session(), _actor(), course_id)  # 404 or 403 before the page
    return render_template("teaching/class_tutor.html", course=get_course(get_session(), course_id),
                           scenes=class_sessions.CLASS_SCENES)


@blueprint.get("/api/courses/<int:course_id>/class-session")
@login_required
@described(answers={200: CLASS_SESSION})
def status(course_id: int) -> ResponseReturnValue:
    """The open session and every seat's robot state."""
    return jsonify(_session_dict(course_id))


@blueprint.post("/api/courses/<int:course_id>/class-session")
@login_required
@described(
    body=obj(scene=about("the scene every student's robot starts in")),
    body_required=False,
    answers={201: CLASS_SESSION},
    refusals=(409, 503),
)
def start(course_id: int) -> ResponseReturnValue:
    """Opens a class session and starts every student's robot in the background."""
    session, manager = get_session(), practice_manager()
    body = request.get_json(silent=True)
    scene = class_sessions.clean_scene(body.get("scene") if isinstance(body, dict) else None)
    opened = class_sessions.start_session(session, _actor(), course_id, manager, scene)  # FarmUnavailable: none kept
    sessions, opened_id = session_factory(current_app), opened.id
    after_commit(lambda: class_sessions.prestart_robots(sessions, manager, opened_id))
    return jsonify(_session_dict(course_id)), 201


@blueprint.delete("/api/courses/<int:course_id>/class-session")
@login_required
@described(answers={200: CLASS_SESSION}, refusals=(409,))
def end(course_id: int) -> ResponseReturnValue:
    """Ends the open session: every student's robot is stopped."""
    owners, manager = class_sessions.end_session(get_session(), _actor(), course_id), practice_manager()

    def stop_robots() -> None:
        for owner_id in owners:
            manager.stop(owner_id)

    after_commit(stop_robots)
    return jsonify(_session_dict(course_id))


def _my_seat_dict() -> dict[str, object]:
    found = class_sessions.my_seat(get_session(), _actor())
    if found is None:
        return {"open": False}
    course, seat = found
    name = practice_name(current_user.username, seat.user_id)
    state = class_sessions.my_seat_state(get_session(), _actor(), seat)
    message = class_sessions.seat_message(seat.message) if state == seat.state else ""
    return {"open": True, "course": {"id": course.id, "code": course.code, "title": course.title},
            "state": state, "message": message, "robot": name,
            "console_url": url_for("lab.console", robot_name=name) if state == "ready" else None}


@blueprint.get("/class")
@login_required
def student_page() -> ResponseReturnValue:
    """The student's class session page: their own robot, and the way to its console."""
    return render_template("teaching/class_student.html")


@blueprint.get("/api/class-session")
@login_required
@described(answers={200: MY_SEAT})
def my_seat() -> ResponseReturnValue:
    """The open class session the user has a seat in, and their robot's state."""
    return jsonify(_my_seat_dict())


@blueprint.post("/api/class-session/robot")
@login_required
@described(answers={202: MY_SEAT}, refusals=(409, 503))
def restart_my_robot() -> ResponseReturnValue:
    """Starts the user's class robot again after they stopped it (or it was lost), in the background."""
    class_session_id = class_sessions.restart_my_robot(get_session(), _actor())
    sessions, manager, user_id = session_factory(current_app), practice_manager(), _actor().id
    after_commit(lambda: class_sessions.prestart_robots(sessions, manager, class_session_id, only_user_id=user_id))
    return jsonify(_my_seat_dict()), 202
