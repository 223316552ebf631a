"""Admin rules for the robots table: add, retitle, readdress, enable and disable. No Flask request state.

The registry (middleware/robots/registry.py) follows the table; the route asks it to refresh after
committing so this process sees the change at once and other workers within a few seconds.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware import events
from middleware.accounts.schemas import (
    InvalidField,
    clean_robot_address,
    clean_robot_kind,
    clean_robot_name,
    clean_robot_title,
)
from middleware.accounts.services import require_admin
from middleware.errors import Refused
from middleware.models import Robot, RobotKindSetting, User
from middleware.models.accounts import utc_now
from middleware.robots.catalog import CAMERA_PICTURES, camera_pictures, default_kind

SceneCheck = Callable[[str], bool | None]
"""Whether the robot called name describes a scene the browser can draw from: True (a simulated robot), False (it
answers but describes none: a robot standing for a real one), None (it does not answer now)."""


@dataclass(frozen=True)
class RobotView:
    """A row of the robots page."""

    id: int
    name: str
    title: str
    address: str
    enabled: bool
    kind: str
    farm_managed: bool = False

    @classmethod
    def of(cls, robot: Robot) -> RobotView:
        """The view of a robots row."""
        return cls(robot.id, robot.name, robot.title, robot.address, robot.enabled, robot.kind, robot.farm_managed)

    def to_dict(self) -> dict[str, object]:
        """The JSON form."""
        return {"id": self.id, "name": self.name, "title": self.title, "address": self.address,
                "enabled": self.enabled, "kind": self.kind, "farm_managed": self.farm_managed}


def list_robots(session: Session, actor: User) -> list[RobotView]:
    """Every robot in the table (admins only)."""
    require_admin(actor)
    return [RobotView.of(r) for r in session.scalars(select(Robot).order_by(Robot.id))]


def add_robot(session: Session, actor: User, name: object, title: object, address: object,
              kind: object = None) -> Robot:
    """Adds an enabled robot (admins only); names are unique; the kind defaults to the name without its number.
    The caller commits."""
    require_admin(actor)
    clean_name = clean_robot_name(name)
    robot = Robot(name=clean_name, title=clean_robot_title(title or clean_name), address=clean_robot_address(address),
                  kind=clean_robot_kind(kind) if kind not in (None, "") else default_kind(clean_name))
    if session.scalar(select(Robot.id).where(Robot.name == clean_name)) is not None:
        raise Refused(409, "robot_exists", gettext("A robot named %(clean_name)s exists already.",
                                                   clean_name=repr(clean_name)), "name")
    session.add(robot)
    session.flush()
    events.announce(session, "robots", robot.name)
    return robot


def update_robot(session: Session, actor: User, robot_id: int, *, title: object = None, address: object = None,
                 enabled: bool | None = None, kind: object = None) -> Robot:
    """Changes a robot's title, address, kind or enabled flag (admins only). The caller commits."""
    require_admin(actor)
    robot = session.get(Robot, robot_id)
    if robot is None:
        raise Refused(404, "unknown_robot", gettext("There is no robot with id %(robot_id)s.", robot_id=robot_id),
                                            "robot_id")
    if title is not None:
        robot.title = clean_robot_title(title)
    if address is not None:
        robot.address = clean_robot_address(address)
    if kind is not None:
        robot.kind = clean_robot_kind(kind)
    if enabled is not None:
        robot.enabled = enabled
    robot.updated_at = utc_now()
    events.announce(session, "robots", robot.name)
    return robot


def kind_pictures(session: Session, actor: User) -> dict[str, str]:
    """Every kind in the robots table with its camera panel's default picture ("video" unless chosen; admins)."""
    require_admin(actor)
    kinds = session.scalars(select(Robot.kind).distinct().order_by(Robot.kind))
    chosen = camera_pictures(session)
    return {kind: chosen.get(kind, "video") for kind in kinds}


def set_kind_picture(session: Session, actor: User, kind: object, picture: object,
                     has_scene: SceneCheck) -> RobotKindSetting:
    """Makes picture ("video" or "drawn") the camera panel's default for every robot of kind (admins only); each
    person may still switch, and their own choice is kept by their browser. "drawn" only for a kind whose robots
    describe a scene (simulated ones, asked through has_scene). The caller commits."""
    require_admin(actor)
    clean_kind = clean_robot_kind(kind)
    if picture not in CAMERA_PICTURES:
        raise InvalidField("picture", gettext("picture must be 'video' (the robot's camera) or 'drawn' (drawn by "
                                              "the browser)."))
    robots = session.scalars(select(Robot).where(Robot.kind == clean_kind).order_by(Robot.id)).all()
    if not robots:
        raise Refused(404, "unknown_kind", gettext("No robot is of the kind %(clean_kind)s.",
                                                   clean_kind=repr(clean_kind)), "kind")
    if picture == "drawn":
        _require_scenes(clean_kind, robots, has_scene)
    setting = session.get(RobotKindSetting, clean_kind)
    if setting is None:
        setting = RobotKindSetting(kind=clean_kind, camera_picture=str(picture))
        session.add(setting)
    else:
        setting.camera_picture, setting.updated_at = str(picture), utc_now()
    session.flush()
    return setting


def _require_scenes(kind: str, robots: Sequence[Robot], has_scene: SceneCheck) -> None:
    """Refuses the drawn picture unless the kind's robots describe a scene: none may answer without one (a robot
    standing for a real one keeps its video) and one at least must answer with one (the farm's robots are simulated
    by construction, answering or not)."""
    answers = {robot.name: True if robot.farm_managed else has_scene(robot.name) for robot in robots}
    without = [name for name, answer in answers.items() if answer is False]
    if without:
        raise Refused(409, "no_scene", gettext("picture cannot be 'drawn' for the kind %(kind)s: %(value)s "
                                               "describes no scene to draw from (a robot standing for a real one "
                                               "keeps its video). Choose 'video'.", kind=kind,
                                               value=', '.join(without)),
                      "picture")
    if True not in answers.values():
        raise Refused(409, "scene_unknown", gettext("picture cannot be 'drawn' for the kind %(kind)s now: none of "
                                                    "its robots answers, so whether they describe a scene to draw "
                                                    "from cannot be checked. Try again once one is online.",
                                                    kind=kind), "picture")
