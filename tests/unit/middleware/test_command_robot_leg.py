"""The robot leg a command reports (Commander.robot_round_trip_ms): the time spent in calls to the robot, a retry
after a forgotten token included, and nothing of the token lookups around them. A stand-in link and a stand-in
clock replace the skill server and time here, so the sum is exact."""

from __future__ import annotations

import pytest

from middleware.access import commands
from middleware.access.commands import Commander
from middleware.robots.refusals import CommandRefused

ROBOT_CALL_S = 0.05
LOOKUP_S = 1.0


class Clock:
    """perf_counter that moves only when told."""

    def __init__(self) -> None:
        self.now_s = 100.0

    def __call__(self) -> float:
        return self.now_s


class StandInLink:
    """A link whose activate_skill takes ROBOT_CALL_S and, if told, refuses the first token as unknown."""

    name = "stand-in"

    def __init__(self, clock: Clock, refuse_first: bool) -> None:
        self.clock, self.refuse_first, self.calls = clock, refuse_first, 0

    def skills(self) -> list:
        return []

    def activate_skill(self, token: str, skill: str, parameters: dict, preempt: bool) -> str:
        self.calls += 1
        self.clock.now_s += ROBOT_CALL_S
        if self.refuse_first and self.calls == 1:
            raise CommandRefused("unauthenticated", "The robot does not know this token.")
        return "goal"


class SlowTokens:
    """A token source whose lookups take LOOKUP_S each, which the robot leg must not count."""

    def __init__(self, clock: Clock) -> None:
        self.clock = clock

    def token(self, fresh: bool) -> str:
        self.clock.now_s += LOOKUP_S
        return "t"

    def resend(self, token: str) -> bool:
        self.clock.now_s += LOOKUP_S
        return True

    def nobody_controls(self) -> bool:
        return False


@pytest.mark.parametrize(("refuse_first", "calls"), [(False, 1), (True, 2)])
def test_the_robot_leg_is_the_time_in_calls_to_the_robot_retry_included(
    monkeypatch: pytest.MonkeyPatch, refuse_first: bool, calls: int
) -> None:
    clock = Clock()
    monkeypatch.setattr(commands.time, "perf_counter", clock)
    link = StandInLink(clock, refuse_first)
    commander = Commander(link, SlowTokens(clock))  # type: ignore[arg-type]
    assert commander.robot_round_trip_ms is None
    assert commander.activate("orientation_control", {}, preempt=True) == "goal"
    assert link.calls == calls
    assert commander.robot_round_trip_ms == pytest.approx(calls * ROBOT_CALL_S * 1000)
