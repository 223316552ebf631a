"""The console's panels, each described by the abstraction it shows (the 2003 paper's visual proxies).

The robot describes its own resources' panels in RobotInfo (camera, odometry, sensors, its map, the drawn lab
view, the battery): each names its kind, words, view and the robot stream that feeds it, which becomes a channel
address here. A SkillController stands for one skill the robot lists. The middleware adds only the panels it owns
itself: driving, the turn, chat and response times (the user's plans used as skills come from plans/). A sensor or
a skill that appears on the skill server appears in the console with no change here or in the client.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from middleware.robots.messages import panel_descriptor, parameter_schema_dict
from protos.telelab.v1 import robot_pb2

# The console's views, each fitting one screen: driving (camera beside the pad), navigating (the map beside the
# skills, which set their goals on it and show their estimates there), sensing (raw readings), talking.
# Every descriptor names its view.
Tab = Literal["drive", "navigate", "sense", "chat"]


@dataclass(frozen=True)
class MiddlewarePanel:
    """A panel of something the middleware owns (a socket of its own), not of the robot."""

    id: str
    kind: str
    title: str
    socket: str
    help: str
    tab: Tab

    def describe(self, robot_name: str) -> dict[str, object]:
        """The panel descriptor."""
        return {"id": self.id, "kind": self.kind, "title": self.title,
                "channel": f"/ws/robots/{robot_name}/{self.socket}", "help": self.help, "tab": self.tab}


# The 2003 paper's skill classes as the catalogue names them (SkillDescription.skill_class).
SKILL_CLASS_WORDS = {
    robot_pb2.SKILL_CLASS_MOTOR: "Motor skill: acts on the wheels from the command alone.",
    robot_pb2.SKILL_CLASS_PERCEPTIVE: "Perceptive skill: interprets the sensors for the other skills.",
    robot_pb2.SKILL_CLASS_SENSORIMOTOR: "Sensorimotor skill: chooses the wheels' commands from what it perceives.",
    robot_pb2.SKILL_CLASS_DELIBERATIVE: "Deliberative skill: reasons over time (plans, builds the map).",
}


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
            "help": _help_with_class(self.skill),
            "tab": "navigate",
            "skill": self.skill.name,
            "skill_class": robot_pb2.SkillClass.Name(self.skill.skill_class).removeprefix("SKILL_CLASS_").lower(),
            "motor": self.skill.motor,
            "schema": [parameter_schema_dict(p) for p in self.skill.parameters],
        }


def _controls(personal: bool) -> list[MiddlewarePanel]:
    turn_help = ("Your personal practice robot: only you see it, so you control it whenever you are here."
                 if personal else "Who controls the robot and who waits.")
    return [MiddlewarePanel("drive", "drive", "Drive", "drive", "Direct control: arrow keys, the pad or a gamepad.",
                            "drive"),
            MiddlewarePanel("queue", "queue", "Turn", "queue", turn_help, "drive")]


def _talk(personal: bool) -> list[MiddlewarePanel]:
    chat_help = ("Your personal practice robot: nobody else reads this chat; notes to yourself."
                 if personal else "Talk with the others connected to this robot.")
    return [MiddlewarePanel("chat", "chat", "Chat", "chat", chat_help, "chat"),
            MiddlewarePanel("response-times", "response-times", "Response times", "drive",
                            "Round trips: browser to middleware, and middleware to the robot.", "sense")]


def robot_panels(robot_name: str, info: robot_pb2.RobotInfo | None, skills: list[robot_pb2.SkillDescription] | None,
                 personal: bool = False, camera_picture: tuple[str, str] = ("", "video"),
                 picture_chosen: str | None = None) -> list[dict[str, object]]:
    """Every panel of the console of robot_name, in the order they are placed: the robot's first panel of the
    drive view (its picture) with the controls beside it, the rest of the robot's panels in its order, its skills,
    then chat and response times. info and skills are None while the robot does not answer.
    personal: a practice robot; camera_picture: the robot's kind and the picture an admin chose as its camera
    panel's default; picture_chosen: the picture this user last chose for robots of that kind, which wins."""
    own = [panel_descriptor(robot_name, panel) for panel in (info.panels if info is not None else [])]
    for descriptor in own:
        if descriptor["kind"] == "camera":
            descriptor["picture"] = {"kind": camera_picture[0] or robot_name, "default": camera_picture[1],
                                     "chosen": picture_chosen}
    lead = next((i + 1 for i, descriptor in enumerate(own) if descriptor["tab"] == "drive"), 0)
    panels = own[:lead] + [panel.describe(robot_name) for panel in _controls(personal)] + own[lead:]
    for skill in skills or []:
        if not skill.direct_drive:  # a direct-drive skill is what the drive pad does: it gets no panel of its own
            panels.append(SkillController(robot_name, skill).describe())
    return panels + [panel.describe(robot_name) for panel in _talk(personal)]


def _help_with_class(skill: robot_pb2.SkillDescription) -> str:
    """The skill's help opening with its class, unless the help names it already ("Perceptive skill: ...")."""
    words = SKILL_CLASS_WORDS.get(skill.skill_class)
    if not words or skill.help.startswith(words.split(":")[0]):
        return skill.help
    return f"{words} {skill.help}".strip()
