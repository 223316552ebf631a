"""Controller token, sequence numbers and value validation of drive commands."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from skill_sim_helpers import TOKEN

from skill_server.errors import InvalidParameter, MissingControllerToken, NotController
from skill_server.sim.drive_gate import DriveGate
from skill_server.sim.robot_model import TELEBOT
from skill_server.sim.world import World


def test_commands_with_another_token_are_refused(empty_world: World) -> None:
    with pytest.raises(NotController, match="not the robot's current controller"):
        empty_world.drive("someone-else", 1, 0.3, 0.0)
    assert empty_world.step_for(0.5).commanded_linear_mps == 0.0


def test_commands_without_a_token_are_refused(empty_world: World) -> None:
    with pytest.raises(MissingControllerToken):
        empty_world.drive("", 1, 0.3, 0.0)


def test_nobody_controls_a_new_robot() -> None:
    with World("empty", realtime=False) as world, pytest.raises(NotController):
        world.drive(TOKEN, 1, 0.1, 0.0)


def test_an_empty_controller_revokes_control_and_stops_the_base(empty_world: World) -> None:
    empty_world.drive(TOKEN, 3, 0.4, 0.0)
    assert empty_world.step_for(1.0).last_applied_sequence == 3
    empty_world.set_controller("")
    snapshot = empty_world.step_for(1.0)
    assert snapshot.commanded_linear_mps == 0.0 and snapshot.last_applied_sequence == 0
    assert not snapshot.deadman_stopped
    with pytest.raises(NotController):
        empty_world.drive(TOKEN, 4, 0.4, 0.0)


def test_older_and_repeated_sequences_are_ignored(empty_world: World) -> None:
    assert empty_world.drive(TOKEN, 5, 0.2, 0.0).applied_sequence == 5
    repeated = empty_world.drive(TOKEN, 5, 0.4, 0.0)
    older = empty_world.drive(TOKEN, 2, -0.4, 0.0)
    assert (repeated.applied_sequence, repeated.linear_mps) == (5, 0.2)
    assert (older.applied_sequence, older.linear_mps) == (5, 0.2)
    snapshot = empty_world.step_for(1.0)
    assert snapshot.last_applied_sequence == 5 and snapshot.commanded_linear_mps == pytest.approx(0.2)


def test_a_new_controller_starts_a_new_sequence(empty_world: World) -> None:
    empty_world.drive(TOKEN, 100, 0.2, 0.0)
    empty_world.set_controller("next-student")
    assert empty_world.drive("next-student", 1, 0.1, 0.0).applied_sequence == 1
    assert empty_world.step_for(0.2).last_applied_sequence == 1


def test_setting_the_same_controller_again_keeps_its_sequence(empty_world: World) -> None:
    empty_world.drive(TOKEN, 10, 0.2, 0.0)
    empty_world.set_controller(TOKEN)
    assert empty_world.drive(TOKEN, 9, 0.1, 0.0).applied_sequence == 10


@pytest.mark.parametrize(
    ("linear_mps", "angular_radps", "field"),
    [
        (math.nan, 0.0, "linear_mps"),
        (math.inf, 0.0, "linear_mps"),
        (-math.inf, 0.0, "linear_mps"),
        (0.51, 0.0, "linear_mps"),
        (-1e300, 0.0, "linear_mps"),
        (0.0, math.nan, "angular_radps"),
        (0.0, 1.6, "angular_radps"),
        (0.0, -1e308, "angular_radps"),
        ("0.1", 0.0, "linear_mps"),
        (True, 0.0, "linear_mps"),
    ],
)
def test_bad_values_are_refused_naming_the_field_and_change_nothing(
    empty_world: World, linear_mps: object, angular_radps: object, field: str
) -> None:
    empty_world.drive(TOKEN, 1, 0.1, 0.0)
    with pytest.raises(InvalidParameter) as refused:
        empty_world.drive(TOKEN, 2, linear_mps, angular_radps)
    assert refused.value.field == field
    assert refused.value.message.startswith(f"{field} must be a finite number between")
    snapshot = empty_world.step_for(0.5)
    assert snapshot.last_applied_sequence == 1 and snapshot.commanded_linear_mps == pytest.approx(0.1)
    assert empty_world.drive(TOKEN, 2, 0.0, 0.0).applied_sequence == 2  # sequence 2 was not used up


def test_the_refusal_states_the_allowed_range() -> None:
    gate = DriveGate(TELEBOT)
    gate.set_controller(TOKEN)
    with pytest.raises(InvalidParameter, match=r"^linear_mps must be a finite number between -0.5 and 0.5 m/s$"):
        gate.submit(TOKEN, 1, 0.6, 0.0)


@given(
    linear=st.floats(allow_nan=True, allow_infinity=True),
    angular=st.floats(allow_nan=True, allow_infinity=True),
)
def test_a_command_is_accepted_exactly_when_both_values_are_finite_and_in_range(linear: float, angular: float) -> None:
    gate = DriveGate(TELEBOT)
    gate.set_controller(TOKEN)
    acceptable = (
        math.isfinite(linear)
        and abs(linear) <= TELEBOT.max_linear_mps
        and math.isfinite(angular)
        and abs(angular) <= TELEBOT.max_angular_radps
    )
    before = gate.latest()
    try:
        ack = gate.submit(TOKEN, 1, linear, angular)
    except InvalidParameter:
        assert not acceptable
        assert gate.latest() == before
    else:
        assert acceptable
        assert (ack.linear_mps, ack.angular_radps) == (linear, angular)
