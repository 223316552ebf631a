"""The battery model alone: how long a charge lasts driving and standing, the dock's recharge, empty's hysteresis."""

from __future__ import annotations

import math

import pytest

from skill_server.errors import InvalidParameter
from skill_server.sim.battery import EMPTY_UNTIL_CHARGE, Battery, BatterySpec, at_dock
from skill_server.sim.robot_model import TELEBOT

TOP_WHEEL_RADPS = TELEBOT.max_linear_mps / TELEBOT.wheel_radius_m
DT_S = 1.0 / 60.0


def run(battery: Battery, seconds: float, left_radps: float, right_radps: float, docked: bool = False) -> float:
    for _ in range(round(seconds / DT_S)):
        battery.advance(DT_S, left_radps, right_radps, docked)
    return battery.state.charge


def test_a_full_charge_lasts_twenty_minutes_of_driving_at_top_speed() -> None:
    battery = Battery(BatterySpec(), TOP_WHEEL_RADPS)
    assert run(battery, 1190.0, TOP_WHEEL_RADPS, TOP_WHEEL_RADPS) > 0.0
    assert run(battery, 20.0, TOP_WHEEL_RADPS, TOP_WHEEL_RADPS) == 0.0 and battery.state.empty


def test_turning_on_the_spot_drains_as_driving_and_standing_still_barely_drains() -> None:
    turning = Battery(BatterySpec(), TOP_WHEEL_RADPS)
    straight = Battery(BatterySpec(), TOP_WHEEL_RADPS)
    assert run(turning, 60.0, -TOP_WHEEL_RADPS, TOP_WHEEL_RADPS) == pytest.approx(
        run(straight, 60.0, TOP_WHEEL_RADPS, TOP_WHEEL_RADPS))
    standing = Battery(BatterySpec(), TOP_WHEEL_RADPS)
    assert 1.0 - run(standing, 3600.0, 0.0, 0.0) == pytest.approx(1 / 24, rel=1e-3)


def test_the_dock_recharges_and_empty_holds_until_five_percent() -> None:
    battery = Battery(BatterySpec(full_drive_s=2.0, recharge_s=10.0), TOP_WHEEL_RADPS)
    run(battery, 3.0, TOP_WHEEL_RADPS, TOP_WHEEL_RADPS)
    assert battery.state.empty
    run(battery, 0.4, 0.0, 0.0, docked=True)
    assert battery.state.charging and 0.0 < battery.state.charge < EMPTY_UNTIL_CHARGE and battery.state.empty
    run(battery, 0.2, 0.0, 0.0, docked=True)
    assert not battery.state.empty
    assert run(battery, 20.0, 0.0, 0.0, docked=True) == 1.0


def test_the_dock_is_a_few_centimetres_wide() -> None:
    assert at_dock(0.03, 0.03, 0.0, 0.0, 0.05) and not at_dock(0.04, 0.04, 0.0, 0.0, 0.05)


@pytest.mark.parametrize("field", ["full_drive_s", "idle_s", "recharge_s", "dock_radius_m"])
@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf])
def test_a_battery_spec_refuses_figures_that_are_not_positive_and_finite(field: str, bad: float) -> None:
    with pytest.raises(InvalidParameter) as refused:
        BatterySpec(**{field: bad})
    assert refused.value.field == field
