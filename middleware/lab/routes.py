"""Lab pages and the robot description API."""

from __future__ import annotations

from dataclasses import dataclass

from flask import Blueprint, abort, current_app, jsonify, render_template, request
from flask.typing import ResponseReturnValue
from flask_login import current_user, login_required

from middleware.access.commands import robot_commands
from middleware.api.contract import ANY, BOOLEAN, OBJECT, STRING, array, described, nullable, number, obj
from middleware.assessment.hidden_obstacles import hiding_book, info_without_obstacles, scene_without_obstacles
from middleware.db import get_session
from middleware.lab.skills import SUPERVISOR_ROLES
from middleware.robots.link import RobotUnavailable
from middleware.robots.messages import robot_info_dict
from middleware.robots.registry import robot_registry
from middleware.robots.scene import scene_dict

blueprint = Blueprint("lab", __name__)


@dataclass(frozen=True)
class RobotCard:
    """What the robot list shows of one robot."""

    name: str
    title: str
    online: bool


@blueprint.get("/lab")
@login_required
def index() -> ResponseReturnValue:
    """The robots of this lab, with whether each answers now."""
    registry = robot_registry()
    robots = [
        RobotCard(name, registry.addresses[name].title, registry.get(name).is_online())  # type: ignore[union-attr]
        for name in registry.names()
    ]
    kinds: dict[str, int] = {}
    for name in registry.names():
        kind = registry.addresses[name].kind
        kinds[kind] = kinds.get(kind, 0) + 1
    pools = sorted((kind, count) for kind, count in kinds.items() if kind and count > 1)
    return render_template("lab/lab_index.html", robots=robots, pools=pools)


@blueprint.get("/lab/<robot_name>")
@login_required
def console(robot_name: str) -> ResponseReturnValue:
    """The lab console of one robot (a practice robot's for its owner only)."""
    if robot_commands().reachable(robot_name, int(current_user.get_id())) is None:
        abort(404)
    title = robot_registry().title(robot_name) or robot_name
    return render_template("lab/console.html", robot_name=robot_name, robot_title=title,
                           supervisor=current_user.role in SUPERVISOR_ROLES)


# Pages poll this; one gRPC call per second per robot answers them all, and "online" lags by at most that.
ROBOT_INFO_MAX_AGE_S = 1.0


@blueprint.get("/api/robots/<robot_name>")
@login_required
@described(answers={200: obj(("name", "online"), name=STRING, title=ANY, online=BOOLEAN, info=ANY)})
def robot_description(robot_name: str) -> ResponseReturnValue:
    """The robot's name, whether it answers, and its figures (null while it does not answer); the scene's obstacle
    boxes left out during the user's obstacle-zone test (middleware/assessment/hidden_obstacles.py)."""
    user_id = int(current_user.get_id())
    link = robot_commands().require(robot_name, user_id)
    try:
        info: dict[str, object] | None = robot_info_dict(link.info(max_age_s=ROBOT_INFO_MAX_AGE_S))
    except RobotUnavailable:
        info = None
    if info is not None and hiding_book(current_app).hides(user_id, get_session()):
        info = info_without_obstacles(info)
    title = robot_registry().title(robot_name)
    return jsonify({"name": robot_name, "title": title, "online": info is not None, "info": info})


# The scene's JSON form (robots/scene.scene_dict); obstacles_hidden only during an obstacle-zone test.
SCENE = obj(("version", "scene_name", "floor", "marks", "blocks", "cylinders", "track", "spawn", "body_radius_m",
             "robot_parts", "camera", "laser", "sonar", "room_cameras"),
            version=STRING, scene_name=STRING, floor=OBJECT, marks=array(OBJECT), blocks=array(OBJECT),
            cylinders=array(OBJECT), track=nullable(OBJECT), spawn=OBJECT, body_radius_m=number(),
            robot_parts=array(OBJECT), camera=OBJECT, laser=OBJECT, sonar=OBJECT, room_cameras=array(OBJECT),
            obstacles_hidden=STRING)

# The scene does not change while a skill server runs; a robot restarted in another scene is noticed within this.
SCENE_RECHECK_S = 5.0


@blueprint.get("/api/robots/<robot_name>/scene")
@login_required
@described(answers={200: SCENE}, refusals=(503,))
def robot_scene(robot_name: str) -> ResponseReturnValue:
    """The robot's static world for the browser's 3D views, to whoever may see the robot (its camera's rule).

    The version is the ETag: a page that holds it gets 304 Not Modified and keeps its copy. During the user's
    obstacle-zone test the obstacles are left out, under a version of its own (assessment/hidden_obstacles.py).
    """
    user_id = int(current_user.get_id())
    link = robot_commands().require(robot_name, user_id)
    scene = link.scene(max_age_s=SCENE_RECHECK_S)
    body = scene_dict(scene)
    if hiding_book(current_app).hides(user_id, get_session()):
        body = scene_without_obstacles(body)
    response = jsonify(body)
    response.set_etag(str(body["version"]))
    response.headers["Cache-Control"] = "private, no-cache"  # kept by the browser, but asked again each time
    return response.make_conditional(request)
