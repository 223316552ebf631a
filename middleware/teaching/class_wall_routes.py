"""The class wall's page and API: a tutor sees every student's robot and acts on one or all; a student raises a
hand. Robot actions go through the one command path (access/commands.py) as the tutor's supervision."""

from __future__ import annotations

import logging
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from flask import Blueprint, current_app, jsonify, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import force_locale, gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware import i18n
from middleware.access.commands import Commander, robot_commands
from middleware.api.contract import BOOLEAN, ID, STRING, about, array, described, nullable, obj, obj_of, one_of, whole
from middleware.courses.services import managed_course
from middleware.db import after_commit, get_session
from middleware.errors import Refused
from middleware.models import User
from middleware.teaching import class_wall

blueprint = Blueprint("class_wall", __name__)
log = logging.getLogger(__name__)
ACTIONS_AT_ONCE = 16  # robots commanded in parallel by a bulk action: a class of 200 stops in a few round trips
SEAT_ACTIONS = ("stop", "dock", "take_over", "give_back", "answer", "note")
CLASS_ACTIONS = ("stop_all", "dock_all", "push")


def _actor() -> User:
    return get_session().get(User, int(current_user.get_id()))  # type: ignore[return-value]


def _body() -> dict[str, Any]:
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise Refused(400, "invalid_field", gettext("Send a JSON object with an action."), "action")
    return body


def _action(body: dict[str, Any], allowed: tuple[str, ...]) -> str:
    action = body.get("action")
    if not isinstance(action, str) or action not in allowed:
        raise Refused(400, "invalid_field", gettext("action must be one of %(actions)s.", actions=", ".join(allowed)),
                      "action")
    return action


def _supervision(robot: str, actor_id: int, field: str) -> Commander:
    return robot_commands().for_supervision(robot, actor_id, supervisor=True, field=field)


HAND = nullable(obj(("text", "raised_at"), text=STRING, raised_at=STRING))
_CHOICE = array(obj(("id", "title"), id=ID, title=STRING))
# The tutor's wall (wall_dict): every seat of the open session and what may be pushed to the class.
WALL = obj(("course", "session_id", "scene", "seats", "choices"),
           course=obj(("id", "code", "title"), id=ID, code=STRING, title=STRING), session_id=ID, scene=STRING,
           seats=array(obj(("user_id", "username", "robot", "seat_state", "message", "hand", "held_by", "testing",
                            "watch_url"),
                           user_id=ID, username=STRING, robot=STRING, seat_state=STRING, message=STRING, hand=HAND,
                           held_by=nullable(STRING), testing=BOOLEAN, watch_url=STRING)),
           choices=obj(("lesson", "exercise", "plan", "test"), lesson=_CHOICE, exercise=_CHOICE, plan=_CHOICE,
                       test=_CHOICE))
# The student's side (class_wall.student_view): only "open" when they have no seat in an open session.
STUDENT_WALL = obj(("open",), open=BOOLEAN, session_id=ID, course_id=ID, robot=STRING, hand=HAND,
                   held_by=nullable(STRING),
                   notices=array(obj_of(("id", "kind", "from", "at"),
                                        {"id": ID, "kind": STRING, "at": STRING, "from": nullable(STRING)})))
SEAT_ACTION = obj(("action", "user_id"), action=STRING, user_id=whole(0), robot=STRING, watch_url=STRING,
                  notice_id=ID)


def wall_dict(course_id: int) -> dict[str, object]:
    """The wall as JSON: the course, the session, every seat, what may be pushed."""
    session, actor = get_session(), _actor()
    course, opened = class_wall.wall_session(session, actor, course_id)
    seats = [{**seat.to_dict(), "watch_url": url_for("lab.console", robot_name=seat.robot)}
             for seat in class_wall.wall_seats(session, opened.id)]
    return {"course": {"id": course.id, "code": course.code, "title": course.title}, "session_id": opened.id,
            "scene": opened.scene, "seats": seats, "choices": class_wall.choices(session, course)}


@blueprint.get("/courses/<int:course_id>/class/wall")
@login_required
def wall_page(course_id: int) -> ResponseReturnValue:
    """The tutor's class wall: every student's robot on one page."""
    session = get_session()
    course = managed_course(session, _actor(), course_id)  # 404 or 403 before the page
    return render_template("teaching/class_wall.html", course=course)


@blueprint.get("/api/courses/<int:course_id>/class-wall")
@login_required
@described(answers={200: WALL}, refusals=(409,))
def wall_state(course_id: int) -> ResponseReturnValue:
    """Every seat of the open class session as the wall shows it (409 when none is open)."""
    return jsonify(wall_dict(course_id))


@blueprint.post("/api/courses/<int:course_id>/class-wall/seats/<int:user_id>")
@login_required
@described(
    body=obj(
        ("action",),
        action=one_of("stop", "dock", "take_over", "give_back", "answer", "note"),
        text=about("note: its sentence"),
        point=about("note: a pointer on the map"),
    ),
    answers={200: SEAT_ACTION},
    refusals=(409, 503),
)
def seat_action(course_id: int, user_id: int) -> ResponseReturnValue:
    """One student's tile: stop, dock, take over, give back, answer the hand, send a note or a pointer."""
    body = _body()
    action = _action(body, SEAT_ACTIONS)
    session, actor = get_session(), _actor()
    result: dict[str, object] = {"action": action, "user_id": user_id}
    if action in ("stop", "dock"):
        _opened, robot = class_wall.seat_robot(session, actor, course_id, user_id)
        commander = _supervision(robot, actor.id, "user_id")
        commander.stop() if action == "stop" else commander.return_to_dock()
        result["robot"] = robot
    elif action == "take_over":
        robot = class_wall.take_over(session, actor, course_id, user_id)
        stopper = _supervision(robot, actor.id, "user_id")
        after_commit(lambda: None if _quietly(robot, stopper.stop) else None)  # the student's last drive stops
        result.update(robot=robot, watch_url=url_for("lab.console", robot_name=robot))
    elif action == "give_back":
        class_wall.give_back(session, actor, course_id, user_id)
    elif action == "answer":
        class_wall.answer_hand(session, actor, course_id, user_id)
    else:
        notice = class_wall.send_note(session, actor, course_id, user_id, body.get("text"), body.get("point"))
        result["notice_id"] = notice.id
    return jsonify(result)


def _quietly(robot: str, act: Callable[[], object]) -> str:
    """act(), its refusal's sentence when refused ("" when done)."""
    try:
        act()
    except Refused as refused:
        return refused.message
    except Exception:  # noqa: BLE001 - one robot's failure must not stop the others'
        log.exception("class wall: an action on %s failed", robot)
        return str(gettext("The robot did not answer."))
    return ""


@blueprint.post("/api/courses/<int:course_id>/class-wall")
@login_required
@described(
    body=obj(
        ("action",),
        action=one_of("stop_all", "dock_all", "push"),
        kind=about("push: lesson, plan or test"),
        id=about("push: its id"),
    ),
    answers={200: obj(("action",), action=STRING)},
    refusals=(409, 503),
)
def class_action(course_id: int) -> ResponseReturnValue:
    """Every robot at once: stop all, dock all; or push a lesson, plan or test to every student."""
    body = _body()
    action = _action(body, CLASS_ACTIONS)
    session, actor = get_session(), _actor()
    _course, opened = class_wall.wall_session(session, actor, course_id)
    if action == "push":
        notice = class_wall.push(session, actor, course_id, body.get("kind"), body.get("id"))
        return jsonify({"action": action, "notice_id": notice.id, **notice.body})
    robots = [robot for _user_id, robot in class_wall.class_robots(session, opened)]
    commands, actor_id = robot_commands(), actor.id
    app, language = current_app._get_current_object(), i18n.current_language()  # type: ignore[attr-defined]

    def act(robot: str) -> str:
        def command() -> object:
            commander = commands.for_supervision(robot, actor_id, supervisor=True)
            return commander.stop() if action == "stop_all" else commander.return_to_dock()
        with app.app_context(), force_locale(language):  # a refusal's sentence in the tutor's language
            return _quietly(robot, command)

    with ThreadPoolExecutor(min(ACTIONS_AT_ONCE, max(1, len(robots))), thread_name_prefix="class-wall") as pool:
        outcomes = dict(zip(robots, pool.map(act, robots), strict=True))
    refused = {robot: message for robot, message in outcomes.items() if message}
    return jsonify({"action": action, "done": len(robots) - len(refused), "refused": refused})


@blueprint.get("/api/class-session/wall")
@login_required
@described(answers={200: STUDENT_WALL}, refusals=(409,))
def my_wall() -> ResponseReturnValue:
    """The student's side of the wall: their hand, who holds their robot, the tutor's notes and pushes."""
    return jsonify(class_wall.student_view(get_session(), _actor()))


@blueprint.post("/api/class-session/hand")
@login_required
@described(body=obj(text=about("an optional sentence")), body_required=False, answers={201: STUDENT_WALL},
           refusals=(409,))
def raise_hand() -> ResponseReturnValue:
    """Raises the student's hand (with an optional sentence, `text`)."""
    body = request.get_json(silent=True)
    text = body.get("text") if isinstance(body, dict) else None
    class_wall.raise_hand(get_session(), _actor(), text)
    return jsonify(class_wall.student_view(get_session(), _actor())), 201


@blueprint.delete("/api/class-session/hand")
@login_required
@described(answers={200: STUDENT_WALL}, refusals=(409,))
def lower_hand() -> ResponseReturnValue:
    """Lowers the student's hand."""
    class_wall.lower_hand(get_session(), _actor())
    return jsonify(class_wall.student_view(get_session(), _actor()))
