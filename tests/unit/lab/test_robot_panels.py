"""The console's panel descriptors: the robot's own panels come from its RobotInfo, the middleware adds its own."""

from __future__ import annotations

from pathlib import Path

from middleware.lab import panels as panels_module
from middleware.lab.panels import robot_panels
from protos.telelab.v1 import robot_pb2
from skill_server.service.convert import panel_to_proto
from skill_server.sim.panels import TELEBOT_PANELS

ROBOT_OWNS = {"camera", "odometry", "map", "lab-view", "room-camera", "sonar", "laser", "low-level"}
MIDDLEWARE_OWNS = {"drive", "queue", "chat", "response-times"}

# What the console received before the robot described its panels (the descriptor list the middleware held).
BEFORE = {
    "camera": ("camera", "Camera", "/ws/robots/lab-1/camera", "drive"),
    "drive": ("drive", "Drive", "/ws/robots/lab-1/drive", "drive"),
    "queue": ("queue", "Turn", "/ws/robots/lab-1/queue", "drive"),
    "odometry": ("odometry", "Odometry", "/ws/robots/lab-1/telemetry", "drive"),
    "map": ("map", "Lab model", "/ws/robots/lab-1/localization", "navigate"),
    "lab-view": ("lab-view", "3D lab view", "/ws/robots/lab-1/telemetry", "navigate"),
    # added since: the room camera (issue 33), a panel the robot describes like the others
    "room-camera": ("room-camera", "Room camera", "/ws/robots/lab-1/telemetry", "navigate"),
    "sonar": ("sonar", "Sonar", "/ws/robots/lab-1/telemetry", "sense"),
    "laser": ("laser", "Laser", "/ws/robots/lab-1/telemetry", "sense"),
    "chat": ("chat", "Chat", "/ws/robots/lab-1/chat", "chat"),
    "response-times": ("response-times", "Response times", "/ws/robots/lab-1/drive", "sense"),
    "low-level": ("low-level", "Low-level commands", "/ws/robots/lab-1/telemetry", "sense"),
}


def telebot_info(*extra: robot_pb2.PanelDescription) -> robot_pb2.RobotInfo:
    """A RobotInfo carrying the simulated Telebot's panels, as its skill server sends them."""
    return robot_pb2.RobotInfo(robot_name="lab-1", panels=[*map(panel_to_proto, TELEBOT_PANELS), *extra])


def by_id(descriptors: list[dict[str, object]]) -> dict[str, dict[str, object]]:
    return {str(d["id"]): d for d in descriptors}


def test_the_telebot_console_gets_the_same_descriptors_as_before_the_robot_described_them() -> None:
    descriptors = robot_panels("lab-1", telebot_info(), [], False, ("telebot", "video"), "drawn")
    shapes = {d["id"]: (d["kind"], d["title"], d["channel"], d["tab"]) for d in descriptors}
    assert shapes == BEFORE
    assert all(isinstance(d["help"], str) and d["help"] for d in descriptors)
    assert by_id(descriptors)["camera"]["picture"] == {"kind": "telebot", "default": "video", "chosen": "drawn"}
    in_view = [d["id"] for d in descriptors if d["tab"] == "drive"]
    assert in_view == ["camera", "drive", "queue", "odometry"], "the pad and the turn sit beside the camera"
    assert [d["id"] for d in descriptors if d["tab"] == "navigate"] == ["map", "lab-view", "room-camera"]


def test_a_sensor_the_robot_describes_gets_a_panel_with_no_middleware_change() -> None:
    thermal = robot_pb2.PanelDescription(id="thermal", kind="thermal", title="Thermal camera",
                                         help="Heat seen ahead.", view=robot_pb2.CONSOLE_VIEW_SENSE,
                                         stream=robot_pb2.ROBOT_STREAM_TELEMETRY)
    gauge = robot_pb2.PanelDescription(id="gauge", kind="gauge", title="Gauge")  # no view, no stream
    descriptors = by_id(robot_panels("lab-2", telebot_info(thermal, gauge), None))
    assert descriptors["thermal"] == {"id": "thermal", "kind": "thermal", "title": "Thermal camera",
                                      "channel": "/ws/robots/lab-2/telemetry", "help": "Heat seen ahead.",
                                      "tab": "sense"}
    assert descriptors["gauge"]["channel"] is None and descriptors["gauge"]["tab"] == "sense"


def test_a_robot_that_cannot_be_asked_gets_the_middleware_panels_only() -> None:
    descriptors = robot_panels("lab-1", None, None)
    assert {d["id"] for d in descriptors} == MIDDLEWARE_OWNS
    assert [d["id"] for d in descriptors][:2] == ["drive", "queue"]


def test_the_middleware_lists_no_panel_of_the_robot_s_resources() -> None:
    source = Path(panels_module.__file__).read_text(encoding="utf-8")
    for panel in TELEBOT_PANELS:
        assert f'"{panel.title}"' not in source and panel.help[:40] not in source, panel.id
    assert {panel.id for panel in TELEBOT_PANELS} == ROBOT_OWNS


def test_a_skill_panel_follows_the_robot_s_panels_and_a_direct_drive_skill_gets_none() -> None:
    skills = [robot_pb2.SkillDescription(name="go_to_goal", title="Go to goal", motor=True),
              robot_pb2.SkillDescription(name="direct_control", direct_drive=True)]
    ids = [d["id"] for d in robot_panels("lab-1", telebot_info(), skills)]
    assert "skill-direct_control" not in ids
    assert ids.index("skill-go_to_goal") > ids.index("low-level") and ids[-2:] == ["chat", "response-times"]


def test_each_skill_panel_names_the_skills_class_of_the_2003_paper() -> None:
    from skill_server.service.convert import skill_to_proto
    from skill_server.sim.robot_model import RobotSpec
    from skill_server.skills.catalog import default_registry

    skills = [skill_to_proto(entry) for entry in default_registry(RobotSpec()).entries()]
    panels = by_id(robot_panels("lab-1", telebot_info(), skills, False, ("telebot", "video"), "drawn"))
    assert panels["skill-go_to_goal"]["skill_class"] == "sensorimotor"
    assert str(panels["skill-go_to_goal"]["help"]).startswith("Sensorimotor skill: ")
    assert str(panels["skill-detect_obstacle"]["help"]).startswith("Perceptive skill: watches the laser")  # once
    assert str(panels["skill-environment_modelling"]["help"]).startswith("Deliberative skill: builds an occupancy")
    assert {panel["skill_class"] for panel in panels.values() if panel["kind"] == "skill"} == {
        "sensorimotor", "perceptive", "deliberative"}  # direct control is the drive pad, a motor skill
