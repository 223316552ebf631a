"""Tour pages and API: the teaching hub, the fully guided player, the editor, and live guided sessions."""

from __future__ import annotations

import time

from flask import Blueprint, current_app, jsonify, render_template, request
from flask_login import current_user, login_required
from sqlalchemy import select

from middleware.db import get_session
from middleware.errors import ApiError
from middleware.models import User
from middleware.models.teaching import GuidedSession, Lesson, Tour
from middleware.practice.control import execute, reference_skills, resolve_target
from middleware.tours import live
from middleware.tours.services import (
    TourInvalid,
    end_session,
    go_to_step,
    hand_control,
    save_tour,
    start_session,
    tour_dict,
    tour_steps,
)

blueprint = Blueprint("tours", __name__)
live.register(blueprint)


def _user_id() -> int:
    return int(current_user.get_id())


def _require_tutor() -> None:
    if current_user.role not in ("tutor", "admin"):
        raise ApiError(403, "not_tutor", "Only tutors write and lead tours.")


def _tour(tour_id: int) -> Tour:
    tour = get_session().get(Tour, tour_id)
    if tour is None:
        raise ApiError(404, "unknown_tour", "There is no such tour.", "tour_id")
    return tour


def _live(session_id: int) -> GuidedSession:
    found = get_session().get(GuidedSession, session_id)
    if found is None:
        raise ApiError(404, "unknown_session", "There is no such class.", "session_id")
    return found


def _invalid(error: TourInvalid) -> ApiError:
    return ApiError(400, "invalid_tour", error.message, error.field)


@blueprint.get("/teaching")
@login_required
def hub():  # type: ignore[no-untyped-def]
    """Tours, lessons, practice robot and the free console."""
    from middleware.robots.registry import robot_registry

    session = get_session()
    return render_template(
        "teaching/hub.html", tours=session.scalars(select(Tour).order_by(Tour.title)).all(),
        lessons=session.scalars(select(Lesson).order_by(Lesson.title)).all(),
        sessions=session.scalars(select(GuidedSession).where(GuidedSession.ended_at.is_(None))).all(),
        lab_robots=robot_registry().names())


@blueprint.get("/tours/<int:tour_id>")
@login_required
def play(tour_id: int):  # type: ignore[no-untyped-def]
    """The fully guided player, on the learner's practice robot."""
    return render_template("teaching/tour.html", tour=_tour(tour_id))


@blueprint.get("/tours/new")
@blueprint.get("/tours/<int:tour_id>/edit")
@login_required
def edit(tour_id: int | None = None):  # type: ignore[no-untyped-def]
    """The tour editor (tutors)."""
    _require_tutor()
    tour = _tour(tour_id) if tour_id is not None else None
    return render_template("teaching/tour_edit.html", tour=tour, tour_data=tour_dict(tour) if tour else None)


@blueprint.get("/api/tours/<int:tour_id>")
@login_required
def tour_api(tour_id: int):  # type: ignore[no-untyped-def]
    """A tour with its steps."""
    return jsonify(tour_dict(_tour(tour_id)))


@blueprint.post("/api/tours")
@blueprint.put("/api/tours/<int:tour_id>")
@login_required
def save(tour_id: int | None = None):  # type: ignore[no-untyped-def]
    """Creates or updates a tour; steps' skills and parameters are checked against the robot's schemas."""
    _require_tutor()
    session = get_session()
    tour = _tour(tour_id) if tour_id is not None else None
    try:
        tour = save_tour(session, request.get_json(silent=True), reference_skills(_user_id()), _user_id(), tour)
    except TourInvalid as error:
        session.rollback()
        raise _invalid(error) from None
    session.commit()
    return jsonify(tour_dict(tour)), 200 if tour_id is not None else 201


@blueprint.post("/api/tours/<int:tour_id>/steps/<int:index>/run")
@login_required
def run_step(tour_id: int, index: int):  # type: ignore[no-untyped-def]
    """Runs the stored command of step index on the learner's target (practice robot or a robot they control)."""
    received_at = time.perf_counter()
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", 'Send a JSON object: {"target": "practice"}.', "body")
    steps = tour_steps(_tour(tour_id))
    if not 0 <= index < len(steps):
        raise ApiError(404, "unknown_step", "The tour has no such step.", "index")
    command = steps[index].command
    if command is None:
        raise ApiError(409, "no_command", "This step runs nothing on the robot.", "index")
    return jsonify(execute(resolve_target(body.get("target"), _user_id()), command, received_at)), 202


# --- live guided sessions ----------------------------------------------------------------------


@blueprint.get("/tours/<int:tour_id>/lead")
@login_required
def start_page(tour_id: int):  # type: ignore[no-untyped-def]
    """The tutor chooses a lab robot (and a course) and starts the class."""
    from middleware.models import Course
    from middleware.robots.registry import robot_registry

    _require_tutor()
    courses = get_session().scalars(select(Course).order_by(Course.title)).all()
    return render_template("teaching/tour_lead.html", tour=_tour(tour_id), robots=robot_registry().names(),
                           courses=courses)


@blueprint.post("/api/tours/<int:tour_id>/sessions")
@login_required
def start_live(tour_id: int):  # type: ignore[no-untyped-def]
    """Starts a live class: {"robot": name, "course_id": id|null}."""
    from middleware.access.coordinator import access_coordinator
    from middleware.models import Course
    from middleware.robots.registry import robot_registry

    _require_tutor()
    tour = _tour(tour_id)
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", 'Send a JSON object: {"robot": "lab-1"}.', "body")
    robot = body.get("robot")
    if not isinstance(robot, str) or robot_registry().get(robot) is None:
        raise ApiError(400, "invalid_field", "Choose one of the lab robots.", "robot")
    course_id = body.get("course_id")
    session = get_session()
    if course_id is not None and (isinstance(course_id, bool) or not isinstance(course_id, int)
                                  or session.get(Course, course_id) is None):
        raise ApiError(400, "invalid_field", "course_id must be one of the courses, or null.", "course_id")
    created = start_session(session, tour, robot, _user_id(), course_id, access_coordinator().now())
    session.commit()
    live.notify(created.id)
    return jsonify(live.state(session, created)), 201


@blueprint.get("/tours/sessions/<int:session_id>")
@login_required
def session_page(session_id: int):  # type: ignore[no-untyped-def]
    """The live class page: the tutor leads, students follow."""
    found = _live(session_id)
    return render_template("teaching/tour_live.html", live=found, tour=_tour(found.tour_id),
                           is_tutor=found.tutor_id == _user_id())


@blueprint.get("/api/tour-sessions/<int:session_id>")
@login_required
def session_api(session_id: int):  # type: ignore[no-untyped-def]
    """The class's state."""
    return jsonify(live.state(get_session(), _live(session_id)))


@blueprint.post("/api/tour-sessions/<int:session_id>")
@login_required
def session_action(session_id: int):  # type: ignore[no-untyped-def]
    """The tutor's actions: {"action": "step", "index": n} | {"action": "control", "user": name|null} | end."""
    from middleware.access.coordinator import access_coordinator

    session = get_session()
    found = _live(session_id)
    if found.tutor_id != _user_id():
        raise ApiError(403, "not_tutor", "Only the tutor who leads this class can do that.")
    if found.ended_at is not None:
        raise ApiError(409, "session_ended", "This class has ended.")
    body = request.get_json(silent=True)
    action = body.get("action") if isinstance(body, dict) else None
    try:
        if action == "step":
            index = body.get("index")  # type: ignore[union-attr]
            if isinstance(index, bool) or not isinstance(index, int):
                raise TourInvalid("index", "index must be a whole number.")
            go_to_step(found, index, len(tour_steps(_tour(found.tour_id))))
        elif action == "control":
            name = body.get("user")  # type: ignore[union-attr]
            user_id = None
            if name is not None:
                user = session.scalar(select(User).where(User.username == name)) if isinstance(name, str) else None
                if user is None:
                    raise TourInvalid("user", "user must be the name of someone in the class, or null.")
                user_id = user.id
            hand_control(found, user_id)
        elif action == "end":
            end_session(found, access_coordinator().now())
        else:
            raise TourInvalid("action", 'action must be "step", "control" or "end".')
    except TourInvalid as error:
        session.rollback()
        raise _invalid(error) from None
    session.commit()
    if action in ("control", "end"):
        try:
            access_coordinator().tick(found.robot_name)  # hand the robot over now, not at the next tick
        except Exception:  # noqa: BLE001 - the ticker applies it shortly anyway
            current_app.logger.info("immediate tick after a class change failed", exc_info=True)
    live.notify(found.id)
    return jsonify(live.state(session, found))
