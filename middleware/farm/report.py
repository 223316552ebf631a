"""`telelab farm ...`: the farm's robots, hosts and load as a table, and the operator's actions on it."""

from __future__ import annotations

from collections.abc import Callable

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.farm.base import FarmRobot, RobotFarm
from middleware.models.farm import PersonalRobotRecord


def status_lines(farm: RobotFarm, sessions: Callable[[], Session]) -> list[str]:
    """The farm's capacity, its hosts, and one line per robot with its owner, host and load."""
    with sessions() as session:
        owners = dict(session.execute(select(PersonalRobotRecord.name, PersonalRobotRecord.owner_name)).all())
    capacity = farm.capacity()
    robots = farm.robots()
    lines = [f"farm: {farm.backend}, {capacity.hosts} host(s), {capacity.running} of {capacity.robots} robots "
             f"running ({capacity.free} free)"]
    nodes = getattr(farm, "nodes", None)
    for node in nodes() if nodes else []:
        count = sum(1 for robot in robots if robot.node == node["node_id"])
        lines.append(f"  host {node['host']} node {node['node_id'][:12]}: {node['cpus']:g} CPUs, {count} robot(s)")
    lines.append(f"{'robot':24} {'owner':16} {'host':16} {'node':12} {'cpu':>6} {'memory':>8}  address")
    lines += [_robot_line(robot, owners.get(robot.name, "-")) for robot in sorted(robots, key=lambda r: r.name)]
    if not robots:
        lines.append("  (no robot runs on the farm)")
    return lines


def _robot_line(robot: FarmRobot, owner: str) -> str:
    cpu = "-" if robot.cpu_share is None else f"{robot.cpu_share * 100:.0f}%"
    memory = "-" if robot.memory_mb is None else f"{robot.memory_mb:.0f}MB"
    restarted = "  (restarted)" if robot.restarted else ""
    return (f"{robot.name:24} {owner:16} {robot.host:16} {robot.node[:12]:12} {cpu:>6} {memory:>8}  "
            f"{robot.address}{restarted}")
