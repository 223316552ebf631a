"""The robot farm for admins: its hosts, capacity and robots with their owners and load; stopping one (the teaching
area owns the farm's users: practice robots and class sessions)."""

from __future__ import annotations

from flask import Blueprint, current_app, flash, jsonify, redirect, render_template, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.accounts.services import require_admin
from middleware.api.contract import BOOLEAN, STRING, array, described, nullable, number, obj, whole
from middleware.db import after_commit, get_session, session_factory
from middleware.errors import Refused
from middleware.farm.base import FarmUnavailable
from middleware.farm.report import farm_status
from middleware.farm.setup import robot_farm
from middleware.teaching.practice_robots import practice_manager

blueprint = Blueprint("farm", __name__)


def _status() -> dict[str, object]:
    require_admin(current_user)
    return farm_status(robot_farm(), session_factory(current_app))


@blueprint.get("/admin/farm")
@login_required
def farm_page() -> ResponseReturnValue:
    """The farm's hosts, capacity and robots (admins); an unreachable farm is said on the page."""
    require_admin(current_user)
    try:
        return render_template("accounts/farm.html", status=_status(), problem=None)
    except FarmUnavailable as error:
        return render_template("accounts/farm.html", status=None, problem=error.message), 503


@blueprint.get("/api/admin/farm")
@login_required
@described(answers={200: obj(
    ("backend", "capacity", "hosts", "robots"), description="farm/report.farm_status",
    backend=STRING,
    capacity=obj(("robots", "running", "free", "hosts"), robots=whole(0), running=whole(0), free=whole(0),
                 hosts=whole(0)),
    hosts=array(obj(("host", "cpus", "node_id", "robots"), host=STRING, cpus=nullable(number()), node_id=STRING,
                    robots=whole(0))),
    robots=array(obj(("name", "owner", "scene", "host", "node", "address", "restarted", "cpu_share", "memory_mb",
                      "elsewhere"),
                     name=STRING, owner=nullable(STRING), scene=STRING, host=STRING, node=STRING, address=STRING,
                     restarted=BOOLEAN, cpu_share=nullable(number()), memory_mb=nullable(number()),
                     elsewhere=BOOLEAN)))}, refusals=(503,))
def farm_api() -> ResponseReturnValue:
    """The farm's state as JSON (admins)."""
    return jsonify(_status())


@blueprint.post("/admin/farm/robots/<robot_name>/stop")
@login_required
def farm_stop(robot_name: str) -> ResponseReturnValue:
    """Stops one robot of the farm (a practice robot's owner sees it stopped)."""
    require_admin(current_user)
    manager = practice_manager()
    practice = manager.begin_stop_named(get_session(), robot_name)  # its row goes with the request's unit of work
    if practice is not None:
        after_commit(lambda: manager.finish_stop(practice))
    elif not robot_farm().stop(robot_name):
        raise Refused(404, "unknown_robot", gettext("The farm runs no robot of that name."), "robot_name")
    flash(gettext("Robot %(robot)s stopped.", robot=robot_name), "success")
    return redirect(url_for("farm.farm_page"), 303)
