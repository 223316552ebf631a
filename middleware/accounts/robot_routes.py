"""The robots table (admins): add robots, change their title, address or enabled flag; whether each answers."""

from __future__ import annotations

from flask import flash, jsonify, redirect, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.accounts import robot_admin
from middleware.accounts.schemas import clean_flag, clean_id
from middleware.accounts.web import blueprint
from middleware.api.contract import OBJECT, STRING, about, array, described, obj
from middleware.db import after_commit, get_session
from middleware.errors import flashed, unless_refused
from middleware.robots.link import CommandRefused, RobotUnavailable
from middleware.robots.registry import robot_registry
from middleware.web import json_body

SCENE_RECHECK_S = 5.0  # as the scene route: a robot restarted in another scene is noticed within this


def _robot_has_scene(name: str) -> bool | None:
    """Whether the robot describes a scene (GetScene answers): None when it does not answer at all, False when it
    answers but not GetScene (a robot standing for a real one)."""
    link = robot_registry().get(name)
    if link is None:
        return None
    try:
        link.scene(max_age_s=SCENE_RECHECK_S)
    except CommandRefused:
        return False
    except RobotUnavailable:
        return False if link.is_online() else None
    return True


def _refresh_robots_after_commit() -> None:
    """The registry reads the robots table in a session of its own: only once the change is committed."""
    after_commit(robot_registry().refresh)


def _robots_page(errors: dict[str, str] | None = None, form: dict[str, str] | None = None,
                 status: int = 200) -> ResponseReturnValue:
    registry = robot_registry()
    views = robot_admin.list_robots(get_session(), current_user)
    links = {v.name: registry.get(v.name) for v in views}
    online = {v.name: bool(v.enabled and (link := links[v.name]) is not None and link.is_online()) for v in views}
    pictures = robot_admin.kind_pictures(get_session(), current_user)
    return render_template("accounts/robots.html", robots=views, online=online, errors=errors or {},
                           form=form or {}, pictures=pictures), status


@blueprint.get("/admin/robots")
@login_required
def robots_page() -> ResponseReturnValue:
    """The robots table with whether each answers, and forms to add and change robots (admins)."""
    return _robots_page()


@blueprint.post("/admin/robots")
@login_required
def robots_add() -> ResponseReturnValue:
    """Adds a robot."""
    form = request.form.to_dict()

    def add() -> ResponseReturnValue:
        robot = robot_admin.add_robot(get_session(), current_user, form.get("name"), form.get("title"),
                                      form.get("address"), form.get("kind"))
        _refresh_robots_after_commit()
        flash(gettext("Robot %(name)s added.", name=robot.name), "success")
        return redirect(url_for("accounts.robots_page"), 303)

    return unless_refused(add, lambda refused: _robots_page({refused.field or "name": refused.message}, form,
                                                            refused.status))


@blueprint.post("/admin/robots/<int:robot_id>")
@login_required
def robots_update(robot_id: int) -> ResponseReturnValue:
    """Changes a robot's title, address or enabled flag (only the fields sent)."""
    form = request.form

    def update() -> ResponseReturnValue:
        robot = robot_admin.update_robot(
            get_session(), current_user, robot_id, title=form.get("title"), address=form.get("address"),
            kind=form.get("kind"), enabled=clean_flag(form["enabled"], "enabled") if "enabled" in form else None)
        _refresh_robots_after_commit()
        flash(gettext("Robot %(name)s saved (enabled).", name=robot.name) if robot.enabled
              else gettext("Robot %(name)s saved (disabled).", name=robot.name), "success")
        return redirect(url_for("accounts.robots_page"), 303)

    return unless_refused(update, flashed(url_for("accounts.robots_page")))


@blueprint.get("/api/admin/robots")
@login_required
@described(answers={200: obj(("robots",), robots=array(OBJECT))})
def api_robots() -> ResponseReturnValue:
    """Every robot in the table (admins)."""
    return jsonify({"robots": [r.to_dict() for r in robot_admin.list_robots(get_session(), current_user)]})


@blueprint.post("/api/admin/robots")
@login_required
@described(
    body=obj(
        ("name", "address"),
        name=about("the robot's name"),
        title=about("shown to people"),
        address=about("host:port of its skill server"),
        kind=about("its kind (pools)"),
    ),
    answers={201: obj(("robot",), robot=OBJECT)},
    refusals=(409,),
)
def api_add_robot() -> ResponseReturnValue:
    """{name, title?, address, kind?}: adds a robot (admins)."""
    data = json_body()
    robot = robot_admin.add_robot(get_session(), current_user, data.get("name"), data.get("title"), data.get("address"),
                                  data.get("kind"))
    _refresh_robots_after_commit()
    return jsonify({"robot": robot_admin.RobotView.of(robot).to_dict()}), 201


@blueprint.patch("/api/admin/robots/<int:robot_id>")
@login_required
@described(
    body=obj(
        title=about("shown to people"),
        address=about("host:port"),
        kind=about("its kind"),
        enabled=about("true or false"),
    ),
    answers={200: obj(("robot",), robot=OBJECT)},
    refusals=(409,),
)
def api_update_robot(robot_id: int) -> ResponseReturnValue:
    """{title?, address?, kind?, enabled?}: changes a robot (admins)."""
    data = json_body()
    robot = robot_admin.update_robot(
        get_session(), current_user, clean_id(robot_id, "robot_id"), title=data.get("title"),
        address=data.get("address"), kind=data.get("kind"),
        enabled=clean_flag(data["enabled"], "enabled") if "enabled" in data else None)
    _refresh_robots_after_commit()
    return jsonify({"robot": robot_admin.RobotView.of(robot).to_dict()})


@blueprint.post("/admin/robot-kinds/<kind>/picture")
@login_required
def robots_kind_picture(kind: str) -> ResponseReturnValue:
    """Sets the camera panel's default picture for the robots of one kind (admins)."""
    picture = request.form.get("picture")

    def update() -> ResponseReturnValue:
        setting = robot_admin.set_kind_picture(get_session(), current_user, kind, picture, _robot_has_scene)
        words = (gettext("the picture drawn by the browser") if setting.camera_picture == "drawn"
                 else gettext("the robot's video"))
        flash(gettext("Robots of the kind %(kind)s now show %(words)s unless a person chooses otherwise.",
                      kind=setting.kind, words=words), "success")
        return redirect(url_for("accounts.robots_page"), 303)

    return unless_refused(update, flashed(url_for("accounts.robots_page")))


@blueprint.get("/api/admin/robot-kinds")
@login_required
@described(
    answers={200: obj(("kinds",), kinds=array(obj(("kind", "camera_picture"), kind=STRING, camera_picture=STRING)))}
)
def api_kind_pictures() -> ResponseReturnValue:
    """Every robot kind with its camera panel's default picture (admins)."""
    return jsonify({"kinds": [{"kind": kind, "camera_picture": picture}
                              for kind, picture in robot_admin.kind_pictures(get_session(), current_user).items()]})


@blueprint.put("/api/admin/robot-kinds/<kind>/picture")
@login_required
@described(
    body=obj(("picture",), picture=about('"video" or "drawn"')),
    answers={200: obj(("kind", "camera_picture"), kind=STRING, camera_picture=STRING)},
)
def api_set_kind_picture(kind: str) -> ResponseReturnValue:
    """{picture: "video" | "drawn"}: the camera panel's default picture for the robots of one kind (admins)."""
    data = json_body()
    setting = robot_admin.set_kind_picture(get_session(), current_user, kind, data.get("picture"), _robot_has_scene)
    return jsonify({"kind": setting.kind, "camera_picture": setting.camera_picture})
