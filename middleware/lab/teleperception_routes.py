"""The teleperception exercise: its page, the robot's evidence grid (read by anyone who may see the robot: it lives
on the robot, so observers see the student's), its reset (supervisory, like the map's) and the raw readings' export.

Reading the grid is what keeps it accumulating on the robot (the skill server integrates readings for 10 s after
each read), so an open exercise page is the switch and an unwatched robot pays nothing.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import TypeVar

from flask import Blueprint, Response, abort, jsonify, render_template, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.access.commands import robot_commands
from middleware.api.contract import OBJECT, STRING, described, file_answer, obj, one_of
from middleware.errors import ApiError
from middleware.lab.perception_export import SensorAngles, readings_csv, readings_mcap
from middleware.lab.skills import SUPERVISOR_ROLES, _supervision
from middleware.robots.link import RobotLink
from middleware.robots.messages import map_dict
from middleware.robots.registry import robot_registry
from protos.telelab.v1 import robot_pb2

blueprint = Blueprint("teleperception", __name__)
Choice = TypeVar("Choice")
READINGS_PER_ANSWER = 600  # the contract's page size (GetPerceptionReadings)
MAX_EXPORTED_SCANS = 2400  # what the robot keeps

SENSORS = {"both": robot_pb2.EVIDENCE_SENSOR_UNSPECIFIED, "sonar": robot_pb2.EVIDENCE_SENSOR_SONAR,
           "laser": robot_pb2.EVIDENCE_SENSOR_LASER}
PARTS = {"both": robot_pb2.EVIDENCE_PART_UNSPECIFIED, "static": robot_pb2.EVIDENCE_PART_STATIC,
         "moving": robot_pb2.EVIDENCE_PART_MOVING}


def _user_id() -> int:
    return int(current_user.get_id())


def _choice(name: str, choices: dict[str, Choice]) -> Choice:
    value = request.args.get(name, "both")
    if value not in choices:
        raise ApiError(400, "invalid_field", gettext("%(name)s must be one of %(choices)s.", name=name,
                                                     choices=", ".join(choices)), name)
    return choices[value]


def evidence_dict(answer: robot_pb2.EvidenceGrid) -> dict[str, object]:
    """The grid (as the map's) with the counts per sensor and part and the robot's odometry pose."""
    pose = answer.odometry
    return {"grid": map_dict(answer.grid), "accumulating": answer.accumulating, "version": answer.version,
            "counts": {"sonar": answer.sonar_scans, "laser": answer.laser_scans, "static": answer.static_scans,
                       "moving": answer.moving_scans},
            "odometry": {"x_m": pose.x_m, "y_m": pose.y_m, "theta_rad": pose.theta_rad}}


@blueprint.get("/lab/<robot_name>/teleperception")
@login_required
def page(robot_name: str) -> ResponseReturnValue:
    """The exercise: static readings, then moving ones, accumulated in the robot's evidence grid."""
    if robot_commands().reachable(robot_name, _user_id()) is None:
        abort(404)
    title = robot_registry().title(robot_name) or robot_name
    return render_template("lab/teleperception.html", robot_name=robot_name, robot_title=title,
                           supervisor=current_user.role in SUPERVISOR_ROLES)


@blueprint.get("/api/robots/<robot_name>/evidence")
@login_required
@described(
    query={"sensor": one_of("both", "sonar", "laser"), "part": one_of("both", "static", "moving")},
    answers={200: obj(("evidence",), evidence=OBJECT)},
    refusals=(503,),
)
def evidence(robot_name: str) -> ResponseReturnValue:
    """?sensor=both|sonar|laser&part=both|static|moving: the chosen layers of the robot's evidence grid."""
    link = robot_commands().require(robot_name, _user_id())
    sensor, part = _choice("sensor", SENSORS), _choice("part", PARTS)
    answer = link.evidence_grid(sensor, part)
    return jsonify({"evidence": evidence_dict(answer)})


@blueprint.delete("/api/robots/<robot_name>/evidence")
@login_required
@described(answers={200: obj(("evidence",), evidence=OBJECT, message=STRING)}, refusals=(409, 503))
def reset(robot_name: str) -> ResponseReturnValue:
    """Forgets the evidence grid and the readings (supervisory: the controller, or a tutor or admin at any time)."""
    robot = _supervision(robot_name)
    answer = robot.reset_evidence()
    return jsonify({"evidence": evidence_dict(answer), "message": gettext("The evidence grid was reset: readings "
                                                                          "gather again from now.")})


def _readings(link: RobotLink) -> tuple[list[robot_pb2.PerceptionScan], SensorAngles]:
    scans: list[robot_pb2.PerceptionScan] = []
    info = link.info()
    while True:
        page = link.perception_readings(scans[-1].index if scans else 0).scans
        scans.extend(page)
        # A short page was all the robot had; readings arriving while it is read do not keep the export going.
        if len(page) < READINGS_PER_ANSWER or len(scans) >= MAX_EXPORTED_SCANS:
            break
    return scans, SensorAngles(info)


def _download(body: str | bytes | Iterator[str], robot_name: str, suffix: str, mimetype: str) -> Response:
    safe = re.sub(r"[^A-Za-z0-9_-]", "_", robot_name)[:64]
    return Response(body, mimetype=mimetype, headers={
        "Content-Disposition": f'attachment; filename="teleperception-{safe}.{suffix}"', "Cache-Control": "no-store"})


@blueprint.get("/api/robots/<robot_name>/readings.csv")
@login_required
@described(answers={200: file_answer("text/csv", "a row per range")}, refusals=(503,))
def readings_as_csv(robot_name: str) -> ResponseReturnValue:
    """The raw readings kept (the last four minutes since the last reset) as CSV, a row per range."""
    link = robot_commands().require(robot_name, _user_id())
    scans, angles = _readings(link)
    return _download(readings_csv(scans, angles), robot_name, "csv", "text/csv")


@blueprint.get("/api/robots/<robot_name>/readings.mcap")
@login_required
@described(answers={200: file_answer("application/octet-stream", "MCAP, topic /teleperception/scan")}, refusals=(503,))
def readings_as_mcap(robot_name: str) -> ResponseReturnValue:
    """The raw readings kept as an MCAP file of JSON messages (topic /teleperception/scan)."""
    link = robot_commands().require(robot_name, _user_id())
    scans, angles = _readings(link)
    return _download(readings_mcap(scans, angles, robot_name), robot_name, "mcap", "application/octet-stream")
