"""The robot agent's abstractions, each describing its own panel (the 2003 paper's visual proxies).

A DynamicRepository stands for a sensor's data, a SkillController for one skill; the console asks
for their descriptors and places the panels without knowing their insides. A skill that appears on
the skill server appears here, and so in the console, with no change to either.
"""

from __future__ import annotations

from dataclasses import dataclass

from middleware.robots.messages import parameter_schema_dict
from protos.telelab.v1 import robot_pb2

# Skills whose panel is not the generic skill panel: direct control is the drive pad.
DIRECT_CONTROL_SKILL = "direct_control"
PERCEPTIVE_HINTS = {"detect_obstacle", "environment_modelling", "localization"}


@dataclass(frozen=True)
class DynamicRepository:
    """A sensor's (or a service's) data with its channel."""

    id: str
    kind: str
    title: str
    channel: str | None
    help: str

    def describe(self) -> dict[str, object]:
        """The panel descriptor."""
        return {"id": self.id, "kind": self.kind, "title": self.title, "channel": self.channel, "help": self.help}


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
            "skill": self.skill.name,
            "motor": self.skill.name not in PERCEPTIVE_HINTS,
            "schema": [parameter_schema_dict(p) for p in self.skill.parameters],
        }


def robot_panels(robot_name: str, skills: list[robot_pb2.SkillDescription] | None,
                 personal: bool = False) -> list[dict[str, object]]:
    """Every panel of the console of robot_name, in the order they are placed (personal: a practice robot)."""
    base = f"/ws/robots/{robot_name}"
    turn_help = ("Your personal practice robot: only you see it, so you control it whenever you are here."
                 if personal else "Who controls the robot and who waits.")
    chat_help = ("Your personal practice robot: nobody else reads this chat; notes to yourself."
                 if personal else "Talk with the others connected to this robot.")
    repositories = [
        DynamicRepository("camera", "camera", "Camera", f"{base}/camera", "The robot's camera, live."),
        DynamicRepository("queue", "queue", "Turn", f"{base}/queue", turn_help),
        DynamicRepository("drive", "drive", "Drive", f"{base}/drive",
                          "Direct control: arrow keys, the pad or a gamepad."),
        DynamicRepository("map", "map", "Lab model", f"{base}/localization",
                          "The lab seen from above: the robot, its readings, the map; click to set a goal."),
        DynamicRepository("odometry", "odometry", "Odometry", f"{base}/telemetry",
                          "Position, heading and speeds integrated from the wheels."),
        DynamicRepository("sonar", "sonar", "Sonar", f"{base}/telemetry", "The ring of sonars, nearest echo each."),
        DynamicRepository("laser", "laser", "Laser", f"{base}/telemetry", "The 180-degree laser scan ahead."),
    ]
    panels = [r.describe() for r in repositories]
    for skill in skills or []:
        if skill.name != DIRECT_CONTROL_SKILL:
            panels.append(SkillController(robot_name, skill).describe())
    panels += [
        DynamicRepository("chat", "chat", "Chat", f"{base}/chat", chat_help).describe(),
        DynamicRepository("response-times", "response-times", "Response times", f"{base}/drive",
                          "Round trips: browser to middleware, and middleware to the robot.").describe(),
    ]
    return panels
