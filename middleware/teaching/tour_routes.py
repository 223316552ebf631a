"""Tour pages and API: the teaching hub, the fully guided player, the editor, and live guided sessions."""

from __future__ import annotations

import time

from flask import Blueprint, current_app, jsonify, render_template, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required
from sqlalchemy import select

from middleware.access.coordinator import access_coordinator
from middleware.accounts.schemas import clean_optional_id
from middleware.api.contract import BOOLEAN, ID, OBJECT, STRING, about, array, described, nullable, obj, one_of, whole
from middleware.bookings.services import tutored_courses
from middleware.db import after_commit, get_session
from middleware.errors import ApiError
from middleware.lab.panels import robot_panels
from middleware.models import Course, User
from middleware.models.teaching import GuidedSession, Lesson, Tour
from middleware.robots.registry import robot_registry
from middleware.teaching import tour_live as live
from middleware.teaching.authority import (
    check_class_start,
    may_run_class,
    require_author_rights,
    require_class_follower,
    require_class_member,
    require_class_rights,
)
from middleware.teaching.progress import note_finished
from middleware.teaching.targets import (
    COMMAND_ANSWER,
    authoring_catalog,
    execute,
    reference_info,
    reference_skills,
    resolve_target,
)
from middleware.teaching.tours import (
    TourInvalid,
    active_session,
    end_session,
    go_to_step,
    hand_control,
    panel_choices,
    save_tour,
    start_session,
    tour_dict,
    tour_steps,
)

blueprint = Blueprint("tours", __name__)
STEP = obj(("title", "text", "panel", "command", "condition"), title=STRING, text=STRING, panel=STRING,
           command=nullable(OBJECT), condition=obj(("type",), type=STRING))
# A tour with its steps (tours.tour_dict).
TOUR = obj(("id", "slug", "title", "summary", "topics", "steps"), id=ID, slug=STRING, title=STRING, summary=STRING,
           topics=array(STRING), steps=array(STEP))
# A live class's state, as every page of it shows it (tour_live.state).
LIVE_STATE = obj(("type", "id", "tour_id", "robot", "tutor", "step_index", "step_count", "step", "controller", "ended",
                  "version", "participants"),
                 type=one_of("state"), id=ID, tour_id=ID, robot=STRING, tutor=nullable(STRING), step_index=whole(),
                 step_count=whole(0), step=nullable(STEP), controller=nullable(STRING), ended=BOOLEAN,
                 version=whole(), participants=array(STRING))


def _user_id() -> int:
    return int(current_user.get_id())


def _actor() -> User:
    return get_session().get(User, _user_id())  # type: ignore[return-value]


def _require_tutor() -> None:
    if current_user.role not in ("tutor", "admin"):
        raise ApiError(403, "not_tutor", gettext("Only tutors write and lead tours."))


def _tour(tour_id: int) -> Tour:
    tour = get_session().get(Tour, tour_id)
    if tour is None:
        raise ApiError(404, "unknown_tour", gettext("There is no such tour."), "tour_id")
    return tour


def _live(session_id: int) -> GuidedSession:
    found = get_session().get(GuidedSession, session_id)
    if found is None:
        raise ApiError(404, "unknown_session", gettext("There is no such class."), "session_id")
    return found


@blueprint.get("/teaching")
@login_required
def hub() -> ResponseReturnValue:
    """Tours, lessons, practice robot and the free console."""
    session = get_session()
    return render_template(
        "teaching/hub.html", tours=session.scalars(select(Tour).order_by(Tour.title)).all(),
        lessons=session.scalars(select(Lesson).order_by(Lesson.title)).all(),
        sessions=session.scalars(select(GuidedSession).where(GuidedSession.ended_at.is_(None))).all(),
        lab_robots=robot_registry().names())


@blueprint.get("/tours/<int:tour_id>")
@login_required
def play(tour_id: int) -> ResponseReturnValue:
    """The fully guided player, on the learner's practice robot."""
    return render_template("teaching/tour.html", tour=_tour(tour_id))


@blueprint.get("/tours/new")
@blueprint.get("/tours/<int:tour_id>/edit")
@login_required
def edit(tour_id: int | None = None) -> ResponseReturnValue:
    """The tour editor (tutors)."""
    _require_tutor()
    tour = _tour(tour_id) if tour_id is not None else None
    if tour is not None:
        require_author_rights(get_session(), _actor(), tour.author_id, "tour")
    return render_template("teaching/tour_edit.html", tour=tour, tour_data=tour_dict(tour) if tour else None,
                           skills=authoring_catalog(_user_id()),
                           panels=_panel_choices([step.panel for step in tour_steps(tour)] if tour else []))


def _panel_choices(in_use: list[str]) -> list[tuple[str, str]]:
    """The panels a step may name, with their titles: a robot's that answers; without one, the middleware's own."""
    try:
        skills = reference_skills(_user_id())
    except ApiError:
        skills = {}
    return panel_choices(robot_panels("tour", reference_info(_user_id()), None), skills, in_use)


@blueprint.get("/api/tours/<int:tour_id>")
@login_required
@described(answers={200: TOUR})
def tour_api(tour_id: int) -> ResponseReturnValue:
    """A tour with its steps."""
    return jsonify(tour_dict(_tour(tour_id)))


@blueprint.post("/api/tours")
@blueprint.put("/api/tours/<int:tour_id>")
@login_required
@described(
    body=obj(title=about("the tour's title"), summary=about("what it shows"), steps=about("its steps")),
    answers={200: TOUR, 201: TOUR},
    refusals=(409, 503),
)
def save(tour_id: int | None = None) -> ResponseReturnValue:
    """Creates or updates a tour; steps' skills and parameters are checked against the robot's schemas."""
    _require_tutor()
    tour = _tour(tour_id) if tour_id is not None else None
    if tour is not None:
        require_author_rights(get_session(), _actor(), tour.author_id, "tour")
    tour = save_tour(get_session(), request.get_json(silent=True), reference_skills(_user_id()), _user_id(), tour)
    return jsonify(tour_dict(tour)), 200 if tour_id is not None else 201


@blueprint.post("/api/tours/<int:tour_id>/steps/<int:index>/run")
@login_required
@described(
    body=obj(target=about('"practice" or a robot the user controls')), answers={202: COMMAND_ANSWER},
    refusals=(409, 503),
)
def run_step(tour_id: int, index: int) -> ResponseReturnValue:
    """Runs the stored command of step index on the learner's target (practice robot or a robot they control)."""
    received_at = time.perf_counter()
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", gettext("Send a JSON object: {\"target\": \"practice\"}."), "body")
    steps = tour_steps(_tour(tour_id))
    if not 0 <= index < len(steps):
        raise ApiError(404, "unknown_step", gettext("The tour has no such step."), "index")
    command = steps[index].command
    if command is None:
        raise ApiError(409, "no_command", gettext("This step runs nothing on the robot."), "index")
    return jsonify(execute(resolve_target(body.get("target"), _user_id()), command, received_at)), 202


@blueprint.post("/api/tours/<int:tour_id>/followed")
@login_required
@described(answers={200: obj(("recorded",), recorded=BOOLEAN)})
def followed(tour_id: int) -> ResponseReturnValue:
    """The player ran the tour to its last step: recorded for the tutors' analytics (and the xAPI statement
    "completed"); a repeat within a minute is not recorded again."""
    tour = _tour(tour_id)
    return jsonify({"recorded": note_finished(get_session(), _user_id(), "tour_followed", tour.id)})


# --- live guided sessions ----------------------------------------------------------------------


@blueprint.get("/tours/<int:tour_id>/lead")
@login_required
def start_page(tour_id: int) -> ResponseReturnValue:
    """The tutor chooses a lab robot and one of the courses they teach, and starts the class."""
    _require_tutor()
    actor = _actor()
    return render_template("teaching/tour_lead.html", tour=_tour(tour_id), robots=robot_registry().names(),
                           courses=tutored_courses(get_session(), actor), may_lead_without_course=actor.role == "admin")


@blueprint.post("/api/tours/<int:tour_id>/sessions")
@login_required
@described(
    body=obj(
        ("robot",),
        robot=about("a lab robot"),
        course_id=about("a course's id, or null"),
        override=about("true or false (admins)"),
    ),
    answers={201: LIVE_STATE},
    refusals=(409, 503),
)
def start_live(tour_id: int) -> ResponseReturnValue:
    """Starts a live class: {"robot": name, "course_id": id|null, "override": false} (teaching/authority.py says
    who may)."""
    _require_tutor()
    tour = _tour(tour_id)
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", gettext("Send a JSON object: {\"robot\": \"lab-1\"}."), "body")
    robot = body.get("robot")
    if not isinstance(robot, str) or robot not in robot_registry().names():
        raise ApiError(400, "invalid_field", gettext("Choose one of the lab robots."), "robot")
    course_id = clean_optional_id(body.get("course_id"), "course_id")
    session = get_session()
    if course_id is not None and session.get(Course, course_id) is None:
        raise ApiError(400, "invalid_field", gettext("course_id must be one of the courses, or null."), "course_id")
    override = body.get("override", False)
    if not isinstance(override, bool):
        raise ApiError(400, "invalid_field", gettext("override must be true or false."), "override")
    actor = _actor()
    check_class_start(session, actor, course_id, override, active_session(session, robot))
    created = start_session(session, tour, robot, actor.id, course_id, access_coordinator().now(),
                            actor.id if override else None)
    live.announce(session, created.id)  # every worker's sockets of the class read it once committed
    return jsonify(live.state(session, created)), 201


@blueprint.get("/tours/sessions/<int:session_id>")
@login_required
def session_page(session_id: int) -> ResponseReturnValue:
    """The live class page: the tutor leads, students follow."""
    found = _live(session_id)
    require_class_follower(get_session(), _actor(), found)
    return render_template("teaching/tour_live.html", live=found, tour=_tour(found.tour_id),
                           is_tutor=may_run_class(get_session(), _actor(), found))


@blueprint.get("/api/tour-sessions/<int:session_id>")
@login_required
@described(answers={200: LIVE_STATE})
def session_api(session_id: int) -> ResponseReturnValue:
    """The class's state."""
    found = _live(session_id)
    require_class_follower(get_session(), _actor(), found)
    return jsonify(live.state(get_session(), found))


@blueprint.post("/api/tour-sessions/<int:session_id>")
@login_required
@described(
    body=obj(
        ("action",),
        action=one_of("step", "control", "end"),
        index=about("the step, for step"),
        user=about("a username or null, for control"),
    ),
    body_required=False,
    answers={200: LIVE_STATE},
    refusals=(409, 503),
)
def session_action(session_id: int) -> ResponseReturnValue:
    """The tutor's actions: {"action": "step", "index": n} | {"action": "control", "user": name|null} | end."""
    session = get_session()
    found = _live(session_id)
    require_class_rights(session, _actor(), found)
    if found.ended_at is not None:
        raise ApiError(409, "session_ended", gettext("This class has ended."))
    body = request.get_json(silent=True)
    body = body if isinstance(body, dict) else {}
    action = body.get("action")
    if action == "step":
        index = body.get("index")
        if isinstance(index, bool) or not isinstance(index, int):
            raise TourInvalid("index", gettext("index must be a whole number."))
        go_to_step(found, index, len(tour_steps(_tour(found.tour_id))))
    elif action == "control":
        name = body.get("user")
        user_id = None
        if name is not None:
            user = session.scalar(select(User).where(User.username == name)) if isinstance(name, str) else None
            if user is None:
                raise TourInvalid("user", gettext("user must be the name of someone in the class, or null."))
            require_class_member(session, found, user)
            user_id = user.id
        hand_control(found, user_id)
    elif action == "end":
        end_session(found, access_coordinator().now())
    else:
        raise TourInvalid("action", gettext("action must be \"step\", \"control\" or \"end\"."))
    live.announce(session, found.id)
    after_commit(lambda: _class_changed(found.id, found.robot_name, handover=action in ("control", "end")))
    return jsonify(live.state(session, found))


def _class_changed(session_id: int, robot_name: str, handover: bool) -> None:
    """Once the change is committed: the robot changes hands now (not at the next tick), and the class's
    sockets are woken (they read it in sessions of their own)."""
    if handover:
        try:
            access_coordinator().tick(robot_name)
        except Exception:  # noqa: BLE001 - the ticker applies it shortly anyway
            current_app.logger.info("immediate tick after a class change failed", exc_info=True)
    live.notify(session_id)
