"""Robot pools: a student waits for, or takes at once, any robot of a kind; admins see every pool's robots with
their load and health, and start or stop the farm's simulated robots of a pool."""

from __future__ import annotations

from typing import Any

from flask import Blueprint, flash, jsonify, redirect, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required
from sqlalchemy import select

from middleware.access import pools
from middleware.access.coordinator import access_coordinator
from middleware.access.pool_seats import PoolSeats
from middleware.accounts.services import require_admin
from middleware.api.contract import ANY, OBJECT, STRING, about, array, described, nullable, number, obj, whole
from middleware.db import after_commit, get_session
from middleware.errors import Refused, flashed, unless_refused
from middleware.farm.base import FarmUnavailable
from middleware.farm.pool_robots import clean_pool_request, remove_pool_rows, start_pool_robots, stop_pool_processes
from middleware.farm.setup import pool_keeper, robot_farm
from middleware.models import Robot, User
from middleware.robots.registry import robot_registry

blueprint = Blueprint("pools", __name__)


def _seats() -> PoolSeats:
    coordinator = access_coordinator()
    coordinator.start_ticker()  # turns must end and pool waiters be bound while people wait
    return PoolSeats(coordinator, get_session(), after_commit)  # the request's unit of work


def _user_id() -> int:
    return int(current_user.get_id())


SEAT = obj(("kind", "robot_name", "position", "queue_size", "robots", "estimated_wait_s", "console_url"),
           description="where the user stands for a kind (access/pool_seats.PoolSeat)",
           kind=STRING, robot_name=nullable(STRING),
           position=whole(-1, description="1.. waiting, 0 bound, -1 not queued"),
           queue_size=whole(0), robots=whole(0), estimated_wait_s=nullable(number()),
           console_url=nullable(STRING))


def _seat_dict(kind: str) -> dict[str, object]:
    seat = _seats().seat(kind, _user_id())
    body = seat.to_dict()
    body["console_url"] = url_for("lab.console", robot_name=seat.robot_name) if seat.robot_name else None
    return body


@blueprint.get("/pools/<kind>")
@login_required
def wait_page(kind: str) -> ResponseReturnValue:
    """The page where a student waits for any robot of kind; it opens the console of the robot bound to them."""
    names = _seats().robots(kind)
    return render_template("lab/pool.html", kind=kind, robot_count=len(names))


@blueprint.get("/api/pools/<kind>/seat")
@login_required
@described(answers={200: SEAT})
def api_seat(kind: str) -> ResponseReturnValue:
    """Where the user stands for kind: bound to a robot, waiting (position, expected wait), or not queued."""
    return jsonify(_seat_dict(kind))


@blueprint.post("/api/pools/<kind>/queue")
@login_required
@described(answers={200: SEAT}, refusals=(409,))
def api_join(kind: str) -> ResponseReturnValue:
    """Waits for any robot of kind (or keeps waiting: the page calls this every few seconds)."""
    _seats().join(kind, _user_id())
    return jsonify(_seat_dict(kind))


@blueprint.post("/api/pools/<kind>/claim")
@login_required
@described(answers={200: SEAT}, refusals=(409, 503))
def api_claim(kind: str) -> ResponseReturnValue:
    """A free robot of kind now; 409 pool_full with the expected wait when none is free (nothing queued)."""
    _seats().claim(kind, _user_id())
    return jsonify(_seat_dict(kind))


@blueprint.delete("/api/pools/<kind>/queue")
@login_required
@described(answers={200: SEAT})
def api_leave(kind: str) -> ResponseReturnValue:
    """Stops waiting for kind."""
    _seats().leave(kind, _user_id())
    return jsonify(_seat_dict(kind))


def _pools_report() -> list[dict[str, Any]]:
    """Every kind with its robots: online, faulted, who controls it, how many wait, the farm's load."""
    session, registry, coordinator = get_session(), robot_registry(), access_coordinator()
    rows = {r.name: r for r in session.scalars(select(Robot).where(Robot.enabled.is_(True)))}
    try:
        load = {robot.name: robot for robot in robot_farm().robots()}
    except FarmUnavailable:
        load = {}
    names_by_id = dict(session.execute(select(User.id, User.username)).all())
    report = []
    grace_s = coordinator.policy.grace_s
    for kind, names in sorted(pools.kinds(session).items()):
        robots = []
        for name in names:
            link, state, farm = registry.get(name), coordinator.snapshot(name), load.get(name)
            online = link is not None and link.is_online()
            robots.append({
                "name": name, "title": rows[name].title, "online": online, "faulted": state.faulted,
                "health": "offline" if not online else ("faulted" if state.faulted else "ready"),
                "controller": names_by_id.get(state.controller_id) if state.controller_id else None,
                "waiting": len(state.waiting_ids), "farm_managed": rows[name].farm_managed,
                "scene": rows[name].scene, "cpu_share": farm.cpu_share if farm else None,
                "memory_mb": farm.memory_mb if farm else None, "host": farm.host if farm else None})
        waiting = pools.waiting(session, kind, coordinator.now(), grace_s)
        report.append({"kind": kind, "robots": robots, "queue": len(waiting),
                       "free": sum(1 for r in robots if r["health"] == "ready" and not r["controller"]
                                   and not r["waiting"]),
                       "farm_managed": any(r["farm_managed"] for r in robots)})
    return report


@blueprint.get("/api/pools")
@login_required
@described(answers={200: obj(("pools",), pools=array(OBJECT))})
def api_pools() -> ResponseReturnValue:
    """The pools a user may wait for: kind, robots, robots answering, free now, pool queue size."""
    return jsonify({"pools": [{"kind": p["kind"], "robots": len(p["robots"]),
                               "online": sum(1 for r in p["robots"] if r["online"]),
                               "free": p["free"], "queue": p["queue"]} for p in _pools_report()]})


@blueprint.get("/admin/pools")
@login_required
def admin_page() -> ResponseReturnValue:
    """Every pool with its robots, load and health; start or stop the farm's robots of a pool (admins)."""
    require_admin(current_user)
    return render_template("accounts/pools.html", pools=_pools_report(), farm_backend=robot_farm().backend,
                           errors={}, form={})


@blueprint.get("/api/admin/pools")
@login_required
@described(answers={200: obj(("pools",), pools=array(OBJECT))})
def admin_api() -> ResponseReturnValue:
    """The pools report as JSON (admins)."""
    require_admin(current_user)
    return jsonify({"pools": _pools_report()})


def _start(kind: object, scene: object, count: object) -> list[str]:
    require_admin(current_user)
    clean_kind, clean_scene, clean_count = clean_pool_request(kind, scene, count)
    started = start_pool_robots(robot_farm(), get_session(), clean_kind, clean_scene, clean_count)
    keeper, registry = pool_keeper(), robot_registry()

    def serve_them() -> None:
        keeper.start_if_needed()  # reads the committed rows
        registry.refresh()

    after_commit(serve_them)
    return started


def _stop(kind: str) -> list[str]:
    require_admin(current_user)
    stopped, farm, registry = remove_pool_rows(get_session(), kind), robot_farm(), robot_registry()

    def stop_processes() -> None:
        stop_pool_processes(farm, stopped)
        registry.refresh()

    after_commit(stop_processes)
    return stopped


@blueprint.post("/admin/pools")
@login_required
def admin_start() -> ResponseReturnValue:
    """Starts simulated robots of a pool on the farm (the form)."""
    form = request.form.to_dict()

    def start() -> ResponseReturnValue:
        started = _start(form.get("kind"), form.get("scene"), form.get("count"))
        flash(gettext("Started %(count)s robot(s): %(names)s.", count=len(started), names=", ".join(started)),
              "success")
        return redirect(url_for("pools.admin_page"), 303)

    def again(refused: Refused) -> ResponseReturnValue:
        return render_template("accounts/pools.html", pools=_pools_report(), farm_backend=robot_farm().backend,
                               errors={refused.field or "kind": refused.message}, form=form), refused.status

    return unless_refused(start, again)


@blueprint.post("/admin/pools/<kind>/stop")
@login_required
def admin_stop(kind: str) -> ResponseReturnValue:
    """Stops the farm's robots of a pool (the form)."""
    def stop() -> ResponseReturnValue:
        stopped = _stop(kind)
        flash(gettext("Stopped %(count)s robot(s) of %(kind)s.", count=len(stopped), kind=kind), "success")
        return redirect(url_for("pools.admin_page"), 303)

    return unless_refused(stop, flashed(url_for("pools.admin_page")))


@blueprint.post("/api/admin/pools")
@login_required
@described(
    body=obj(
        ("kind", "scene", "count"),
        kind=about("the pool's kind"),
        scene=about("a scene's name"),
        count=about("how many robots"),
    ),
    answers={201: obj(("started",), started=ANY)},
    refusals=(409, 503),
)
def admin_api_start() -> ResponseReturnValue:
    """{kind, scene, count}: starts simulated robots of a pool on the farm (admins)."""
    data = request.get_json(silent=True)
    if not isinstance(data, dict):
        raise Refused(400, "invalid_field", gettext("Send a JSON object with kind, scene and count."), "kind")
    return jsonify({"started": _start(data.get("kind"), data.get("scene"), data.get("count"))}), 201


@blueprint.delete("/api/admin/pools/<kind>")
@login_required
@described(answers={200: obj(("stopped",), stopped=ANY)}, refusals=(503,))
def admin_api_stop(kind: str) -> ResponseReturnValue:
    """Stops the farm's robots of a pool (admins)."""
    return jsonify({"stopped": _stop(kind)})
