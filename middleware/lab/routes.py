"""Lab pages and the robot description API."""

from __future__ import annotations

from dataclasses import dataclass

from flask import Blueprint, abort, jsonify, render_template
from flask_login import login_required

from middleware.errors import ApiError
from middleware.robots.link import RobotUnavailable
from middleware.robots.messages import robot_info_dict
from middleware.robots.registry import robot_registry

blueprint = Blueprint("lab", __name__)


@dataclass(frozen=True)
class RobotCard:
    """What the robot list shows of one robot."""

    name: str
    title: str
    online: bool


@blueprint.get("/lab")
@login_required
def index():  # type: ignore[no-untyped-def]
    """The robots of this lab, with whether each answers now."""
    registry = robot_registry()
    robots = [
        RobotCard(name, registry.addresses[name].title, registry.get(name).is_online())  # type: ignore[union-attr]
        for name in registry.names()
    ]
    return render_template("lab_index.html", robots=robots)


@blueprint.get("/lab/<robot_name>")
@login_required
def console(robot_name: str):  # type: ignore[no-untyped-def]
    """The lab console of one robot (a practice robot's for its owner only: the registry checks)."""
    title = robot_registry().title(robot_name)
    if title is None:
        abort(404)
    return render_template("console.html", robot_name=robot_name, robot_title=title)


# Pages poll this; one gRPC call per second per robot answers them all, and "online" lags by at most that.
ROBOT_INFO_MAX_AGE_S = 1.0


@blueprint.get("/api/robots/<robot_name>")
@login_required
def robot_description(robot_name: str):  # type: ignore[no-untyped-def]
    """The robot's name, whether it answers, and its figures (null while it does not answer)."""
    registry = robot_registry()
    link = registry.get(robot_name)
    if link is None:
        raise ApiError(404, "unknown_robot", f"There is no robot named {robot_name!r}.", "robot_name")
    try:
        info: dict[str, object] | None = robot_info_dict(link.info(max_age_s=ROBOT_INFO_MAX_AGE_S))
    except RobotUnavailable:
        info = None
    return jsonify({"name": robot_name, "title": registry.title(robot_name), "online": info is not None, "info": info})
