"""The robot agent's abstractions, each describing its own panel (the 2003 paper's visual proxies).

A DynamicRepository stands for a sensor's data, a SkillController for one skill; the console asks
for their descriptors and places the panels without knowing their insides. A skill that appears on
the skill server appears here, and so in the console, with no change to either.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from middleware.robots.messages import parameter_schema_dict
from protos.telelab.v1 import robot_pb2

# The console's views, each fitting one screen: driving (camera beside the pad), navigating (the map beside the
# skills, which set their goals on it and show their estimates there), sensing (raw readings), talking.
# Every descriptor names its view.
Tab = Literal["drive", "navigate", "sense", "chat"]


@dataclass(frozen=True)
class DynamicRepository:
    """A sensor's (or a service's) data with its channel."""

    id: str
    kind: str
    title: str
    channel: str | None
    help: str
    tab: Tab
    extra: tuple[tuple[str, object], ...] = ()  # what this kind of panel needs besides (the camera: its picture)

    def describe(self) -> dict[str, object]:
        """The panel descriptor."""
        return {"id": self.id, "kind": self.kind, "title": self.title, "channel": self.channel, "help": self.help,
                "tab": self.tab, **dict(self.extra)}


@dataclass(frozen=True)
class SkillController:
    """One skill of the robot: activate, deactivate, watch."""

    robot_name: str
    skill: robot_pb2.SkillDescription

    def describe(self) -> dict[str, object]:
        """The panel descriptor, with the skill's parameter schema."""
        return {
            "id": f"skill-{self.skill.name}",
            "kind": "skill",
            "title": self.skill.title or self.skill.name.replace("_", " ").capitalize(),
            "channel": f"/ws/robots/{self.robot_name}/goals",
            "help": self.skill.help,
            "tab": "navigate",
            "skill": self.skill.name,
            "motor": self.skill.motor,
            "schema": [parameter_schema_dict(p) for p in self.skill.parameters],
        }


def robot_panels(robot_name: str, skills: list[robot_pb2.SkillDescription] | None,
                 personal: bool = False, camera_picture: tuple[str, str] = ("", "video"),
                 picture_chosen: str | None = None) -> list[dict[str, object]]:
    """Every panel of the console of robot_name, in the order they are placed (personal: a practice robot;
    camera_picture: the robot's kind and the picture an admin chose as its camera panel's default;
    picture_chosen: the picture this user last chose for robots of that kind, which wins over the default)."""
    base = f"/ws/robots/{robot_name}"
    turn_help = ("Your personal practice robot: only you see it, so you control it whenever you are here."
                 if personal else "Who controls the robot and who waits.")
    chat_help = ("Your personal practice robot: nobody else reads this chat; notes to yourself."
                 if personal else "Talk with the others connected to this robot.")
    repositories = [
        DynamicRepository("camera", "camera", "Camera", f"{base}/camera",
                          "What the robot sees: its camera's video, or the view your browser draws from its pose.",
                          "drive",
                          (("picture", {"kind": camera_picture[0] or robot_name, "default": camera_picture[1],
                                        "chosen": picture_chosen}),)),
        DynamicRepository("drive", "drive", "Drive", f"{base}/drive",
                          "Direct control: arrow keys, the pad or a gamepad.", "drive"),
        DynamicRepository("queue", "queue", "Turn", f"{base}/queue", turn_help, "drive"),
        DynamicRepository("odometry", "odometry", "Odometry", f"{base}/telemetry",
                          "Position, heading and speeds integrated from the wheels.", "drive"),
        DynamicRepository("map", "map", "Lab model", f"{base}/localization",
                          "The lab seen from above: the robot, its readings, the map; click to set a goal.",
                          "navigate"),
        DynamicRepository("lab-view", "lab-view", "3D lab view", f"{base}/telemetry",
                          "The lab in 3D, drawn by your browser: the robot at its odometry pose, its laser hits and "
                          "sonar cones, the goal and the path planned to it, the map on the floor. Drag to turn it.",
                          "navigate"),
        DynamicRepository("sonar", "sonar", "Sonar", f"{base}/telemetry", "The ring of sonars, nearest echo each.",
                          "sense"),
        DynamicRepository("laser", "laser", "Laser", f"{base}/telemetry", "The 180-degree laser scan ahead.", "sense"),
    ]
    panels = [r.describe() for r in repositories]
    for skill in skills or []:
        if not skill.direct_drive:  # a direct-drive skill is what the drive pad does: it gets no panel of its own
            panels.append(SkillController(robot_name, skill).describe())
    panels += [
        DynamicRepository("chat", "chat", "Chat", f"{base}/chat", chat_help, "chat").describe(),
        DynamicRepository("response-times", "response-times", "Response times", f"{base}/drive",
                          "Round trips: browser to middleware, and middleware to the robot.", "sense").describe(),
        DynamicRepository("low-level", "low-level", "Low-level commands", f"{base}/telemetry",
                          "The battery, the velocity ceilings and the watchdog timeout.", "sense").describe(),
    ]
    return panels
