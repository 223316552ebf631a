"""The robot's resources as a console shows them (the 2003 paper's visual proxies): each describes its own panel.

GetRobotInfo sends these in order; the middleware turns each stream into its channel address and adds only the
panels it owns itself (driving, the turn, chat, response times). A sensor added to the robot adds its panel here,
with no change to the middleware.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

View = Literal["drive", "navigate", "sense", "chat"]
Stream = Literal["camera", "telemetry", "localization"]


@dataclass(frozen=True)
class PanelSpec:
    """One resource's panel: its id, the kind the console draws it with, words for people, view and stream."""

    id: str
    kind: str
    title: str
    help: str
    view: View
    stream: Stream | None = None


CAMERA = PanelSpec("camera", "camera", "Camera",
                   "What the robot sees: its camera's video, or the view your browser draws from its pose.",
                   "drive", "camera")
ODOMETRY = PanelSpec("odometry", "odometry", "Odometry", "Position, heading and speeds integrated from the wheels.",
                     "drive", "telemetry")
MAP = PanelSpec("map", "map", "Lab model",
                "The lab seen from above: the robot, its readings, the map; click to set a goal.",
                "navigate", "localization")
LAB_VIEW = PanelSpec("lab-view", "lab-view", "3D lab view",
                     "The lab in 3D, drawn by your browser: the robot at its odometry pose, its laser hits and "
                     "sonar cones, the goal and the path planned to it, the map on the floor. Drag to turn it.",
                     "navigate", "telemetry")
SONAR = PanelSpec("sonar", "sonar", "Sonar", "The ring of sonars, nearest echo each.", "sense", "telemetry")
LASER = PanelSpec("laser", "laser", "Laser", "The 180-degree laser scan ahead.", "sense", "telemetry")
ROOM_CAMERA = PanelSpec("room-camera", "room-camera", "Room camera",
                        "The robot seen from a camera on the room's wall, drawn by your browser where the robot truly "
                        "stands. Pan, tilt and zoom it with the buttons, the arrow keys, + and -, or by dragging.",
                        "navigate", "telemetry")
LOW_LEVEL = PanelSpec("low-level", "low-level", "Low-level commands",
                      "The battery, the velocity ceilings and the watchdog timeout.", "sense", "telemetry")

LINE_SENSOR = PanelSpec("line-sensor", "line-sensor", "Line sensor",
                         "Reflectance cells under the robot's front, left to right: 1 over the tape, 0 on bare floor. "
                         "Shown in scenes with a line of tape.", "sense", "telemetry")

TELEBOT_PANELS: tuple[PanelSpec, ...] = (CAMERA, ODOMETRY, MAP, LAB_VIEW, ROOM_CAMERA, SONAR, LASER, LOW_LEVEL)
