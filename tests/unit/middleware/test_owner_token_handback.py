"""A practice robot that forgot its owner's token (it restarted) is handed the token again, but only while the
registry still says the robot at that address is the owner's: a farm that gave the address to another student's
robot must not get the first owner's token from a channel left open. A stand-in registry and link replace the
farm and the skill server."""

from __future__ import annotations

import pytest

from middleware.access.commands import RobotCommands
from middleware.robots.refusals import CommandRefused
from middleware.robots.registry import PersonalRobot

OWNER_ID = 7


class ForgetfulLink:
    """A robot that refuses the first command as from an unknown token, and counts the tokens it is handed."""

    name = "practice-pupil"

    def __init__(self, address: str) -> None:
        self.address, self.calls, self.handed = address, 0, []

    def skills(self) -> list:
        return []

    def activate_skill(self, token: str, skill: str, parameters: dict, preempt: bool) -> str:
        self.calls += 1
        if self.calls == 1:
            raise CommandRefused("unauthenticated", "The robot does not know this token.")
        return "goal"

    def set_controller(self, token: str) -> None:
        self.handed.append(token)


class Registry:
    """Whatever the farm says now about the one personal robot name."""

    def __init__(self, robot: PersonalRobot | None) -> None:
        self.robot = robot

    def is_personal_name(self, name: str) -> bool:
        return name.startswith("practice-")

    def personal(self, name: str) -> PersonalRobot | None:
        return self.robot


def commander_and_registry(link: ForgetfulLink):
    registry = Registry(PersonalRobot(link, "Practice robot", OWNER_ID, "owner-token"))  # type: ignore[arg-type]
    commands = RobotCommands(registry, coordinator=None)  # type: ignore[arg-type]
    return commands.for_user(link.name, OWNER_ID), registry


def test_a_robot_that_forgot_its_owners_token_is_handed_it_again() -> None:
    link = ForgetfulLink("127.0.0.1:5001")
    commander, _registry = commander_and_registry(link)
    assert commander.activate("orientation_control", {}, preempt=True) == "goal"
    assert link.handed == ["owner-token"]


@pytest.mark.parametrize("farm_now", ["stopped", "another owner's robot at the address", "moved to another address"])
def test_the_owners_token_is_not_handed_to_a_robot_that_is_no_longer_theirs(farm_now: str) -> None:
    link = ForgetfulLink("127.0.0.1:5001")
    commander, registry = commander_and_registry(link)
    if farm_now == "stopped":
        registry.robot = None
    elif farm_now == "another owner's robot at the address":
        registry.robot = PersonalRobot(link, "Practice robot", OWNER_ID + 1, "someone-elses-token")  # type: ignore[arg-type]
    else:
        registry.robot = PersonalRobot(ForgetfulLink("127.0.0.1:5002"), "Practice robot", OWNER_ID,  # type: ignore[arg-type]
                                       "owner-token")
    with pytest.raises(CommandRefused):
        commander.activate("orientation_control", {}, preempt=True)
    assert link.handed == []
