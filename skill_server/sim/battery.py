"""The simulated battery: a charge that motion drains and standing at the dock refills."""

from __future__ import annotations

import math
from dataclasses import dataclass

from skill_server.errors import InvalidParameter

# An empty battery stays "empty" until recharged to this fraction, so a robot that has just left its dock
# does not run dry again after a centimetre.
EMPTY_UNTIL_CHARGE = 0.05


@dataclass(frozen=True)
class BatterySpec:
    """The battery's figures; tests use a tiny one (full_drive_s of a few seconds)."""

    full_drive_s: float = 1200.0  # [s] a full charge lasts this long driving straight at the robot's top speed
    idle_s: float = 24 * 3600.0  # [s] a full charge lasts this long standing still (electronics only)
    recharge_s: float = 120.0  # [s] from empty to full at the dock
    dock_radius_m: float = 0.05  # [m] the robot charges while its centre is this close to the dock
    initial_charge: float = 1.0  # 0..1 of full

    def __post_init__(self) -> None:
        for name in ("full_drive_s", "idle_s", "recharge_s", "dock_radius_m"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
                raise InvalidParameter(name, f"{name} must be a finite number above 0")
        if not 0.0 <= self.initial_charge <= 1.0:
            raise InvalidParameter("initial_charge", "initial_charge must be between 0 and 1")


@dataclass(frozen=True)
class BatteryState:
    """The charge as telemetry reports it."""

    charge: float  # 0..1 of full
    charging: bool
    empty: bool


FULL_BATTERY = BatteryState(1.0, False, False)


class Battery:
    """Drain = idle term + a term proportional to the wheels' speeds; charging at the dock overrides both."""

    def __init__(self, spec: BatterySpec, top_wheel_speed_radps: float) -> None:
        self.spec = spec
        idle_per_s = 1.0 / spec.idle_s
        # At top speed both wheels turn at top_wheel_speed_radps: the two terms then last full_drive_s.
        self._idle_per_s = idle_per_s
        self._per_wheel_rad = max(0.0, 1.0 / spec.full_drive_s - idle_per_s) / (2.0 * top_wheel_speed_radps)
        self._charge = min(1.0, max(0.0, spec.initial_charge))
        self._empty = self._charge <= 0.0
        self._charging = False

    @property
    def state(self) -> BatteryState:
        """The charge now."""
        return BatteryState(self._charge, self._charging, self._empty)

    def advance(self, dt_s: float, left_radps: float, right_radps: float, at_dock: bool) -> BatteryState:
        """The charge after dt_s with the wheels turning at these speeds (at_dock: charging instead)."""
        self._charging = at_dock
        if at_dock:
            self._charge = min(1.0, self._charge + dt_s / self.spec.recharge_s)
        else:
            drain = self._idle_per_s + self._per_wheel_rad * (abs(left_radps) + abs(right_radps))
            self._charge = max(0.0, self._charge - drain * dt_s)
        if self._charge <= 0.0:
            self._empty = True
        elif self._empty and self._charge >= EMPTY_UNTIL_CHARGE:
            self._empty = False
        return self.state


def at_dock(x_m: float, y_m: float, dock_x_m: float, dock_y_m: float, radius_m: float) -> bool:
    """Whether a robot centred at (x_m, y_m) stands on the dock."""
    return math.hypot(x_m - dock_x_m, y_m - dock_y_m) <= radius_m
