"""Which farm this lab uses (TELELAB_FARM, TELELAB_RAY_ADDRESS), made once per app."""

from __future__ import annotations

import os
import time

from flask import Flask, current_app

from middleware.config import ConfigError
from middleware.db import session_factory
from middleware.farm.base import RobotFarm
from middleware.farm.costs import robot_cpu_share
from middleware.farm.pool_robots import PoolKeeper
from middleware.robots.registry import robot_registry

_EXTENSION_KEY = "telelab.farm"
_KEEPER_KEY = "telelab.pool_keeper"
RECHECK_POOLS_S = 30.0
BACKENDS = ("local", "ray")


def build_farm(environ: dict[str, str] | None = None) -> RobotFarm:
    """The farm the settings name; ConfigError names the setting at fault. Nothing is contacted yet."""
    env = os.environ if environ is None else environ
    backend = env.get("TELELAB_FARM", "local").strip().lower()
    if backend not in BACKENDS:
        raise ConfigError(f"TELELAB_FARM must be one of {', '.join(BACKENDS)}, not {backend!r}.")
    cpu_share = robot_cpu_share(env)
    if backend == "local":
        from middleware.farm.owner import ADDRESS_VARIABLE, KEY_VARIABLE, SharedLocalFarm

        if env.get(ADDRESS_VARIABLE):  # a worker of `telelab up --workers N`: the launcher's owner holds the robots
            return SharedLocalFarm(env[ADDRESS_VARIABLE], env.get(KEY_VARIABLE, ""))
        from middleware.farm.local import LocalProcessFarm

        return LocalProcessFarm(cpu_share=cpu_share)
    address = env.get("TELELAB_RAY_ADDRESS", "").strip()
    if not address or ":" not in address:
        raise ConfigError("TELELAB_RAY_ADDRESS must give the Ray head as host:port when TELELAB_FARM=ray "
                          "(`telelab up --farm ray` starts a local one).")
    from middleware.farm.ray_farm import RayFarm

    return RayFarm(address, cpu_share=cpu_share)


def init_app(app: Flask, farm: RobotFarm | None = None) -> RobotFarm:
    """Gives app its farm (from app.config["FARM"], the argument, or the environment)."""
    chosen = farm or app.config.get("FARM") or build_farm()
    app.extensions[_EXTENSION_KEY] = chosen
    keeper = app.extensions[_KEEPER_KEY] = PoolKeeper(chosen, session_factory(app),
                                                      lambda: robot_registry(app).refresh())
    looked_at = [-RECHECK_POOLS_S]

    @app.before_request
    def keep_pools_once_serving() -> None:
        # A process keeps the pools' farm robots once it serves requests (`telelab` commands never do); until it
        # has some, it looks again now and then, as `telelab farm start --pool` may add them from outside.
        now = time.monotonic()
        if now - looked_at[0] >= RECHECK_POOLS_S:
            looked_at[0] = now if not keeper.start_if_needed() else float("inf")

    return chosen


def pool_keeper(app: Flask | None = None) -> PoolKeeper:
    """The keeper of app's pool robots (or of the current app's)."""
    return (app or current_app).extensions[_KEEPER_KEY]


def robot_farm(app: Flask | None = None) -> RobotFarm:
    """The farm of app (or of the current app)."""
    return (app or current_app).extensions[_EXTENSION_KEY]
