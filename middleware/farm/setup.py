"""Which farm this lab uses (TELELAB_FARM, TELELAB_RAY_ADDRESS), made once per app."""

from __future__ import annotations

import os

from flask import Flask, current_app

from middleware.config import ConfigError
from middleware.farm.base import RobotFarm

_EXTENSION_KEY = "telelab.farm"
BACKENDS = ("local", "ray")


def build_farm(environ: dict[str, str] | None = None) -> RobotFarm:
    """The farm the settings name; ConfigError names the setting at fault. Nothing is contacted yet."""
    env = os.environ if environ is None else environ
    backend = env.get("TELELAB_FARM", "local").strip().lower()
    if backend not in BACKENDS:
        raise ConfigError(f"TELELAB_FARM must be one of {', '.join(BACKENDS)}, not {backend!r}.")
    if backend == "local":
        from middleware.farm.local import LocalProcessFarm

        return LocalProcessFarm()
    address = env.get("TELELAB_RAY_ADDRESS", "").strip()
    if not address or ":" not in address:
        raise ConfigError("TELELAB_RAY_ADDRESS must give the Ray head as host:port when TELELAB_FARM=ray "
                          "(`telelab up --farm ray` starts a local one).")
    from middleware.farm.ray_farm import RayFarm

    return RayFarm(address)


def init_app(app: Flask, farm: RobotFarm | None = None) -> RobotFarm:
    """Gives app its farm (from app.config["FARM"], the argument, or the environment)."""
    chosen = farm or app.config.get("FARM") or build_farm()
    app.extensions[_EXTENSION_KEY] = chosen
    return chosen


def robot_farm(app: Flask | None = None) -> RobotFarm:
    """The farm of app (or of the current app)."""
    return (app or current_app).extensions[_EXTENSION_KEY]
