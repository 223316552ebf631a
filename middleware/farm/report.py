"""The farm's state for people: capacity, hosts and every robot with its owner and load (the admin page, the
API and `telelab farm status`), read from the farm and the personal robots' table."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.farm.base import RobotFarm
from middleware.models import Robot
from middleware.models.farm import PersonalRobotRecord


def farm_status(farm: RobotFarm, sessions: Callable[[], Session]) -> dict[str, Any]:
    """{backend, capacity: {robots, running, free, hosts}, hosts: [...], robots: [...]} of the farm now; a robot
    recorded but run by another process's local farm is listed with elsewhere=True and no load. A pool's robot
    has "pool <kind>" as its owner."""
    with sessions() as session:
        records: list[Any] = list(session.execute(select(PersonalRobotRecord.name, PersonalRobotRecord.owner_name,
                                                          PersonalRobotRecord.scene,
                                                          PersonalRobotRecord.address)).all())
        records += session.execute(select(Robot.name, "pool " + Robot.kind, Robot.scene, Robot.address)
                                   .where(Robot.farm_managed.is_(True))).all()
    owners = {name: owner for name, owner, _scene, _address in records}
    capacity = farm.capacity()
    robots = sorted(farm.robots(), key=lambda robot: robot.name)
    nodes = getattr(farm, "nodes", None)
    hosts = nodes() if nodes else [{"host": "localhost", "cpus": None, "node_id": "localhost"}]
    return {
        "backend": farm.backend,
        "capacity": {"robots": capacity.robots, "running": capacity.running, "free": capacity.free,
                     "hosts": capacity.hosts},
        "hosts": [{**host, "robots": sum(1 for robot in robots if robot.node == host["node_id"])} for host in hosts],
        "robots": [{"name": robot.name, "owner": owners.get(robot.name), "scene": robot.scene, "host": robot.host,
                    "node": robot.node, "address": robot.address, "restarted": robot.restarted,
                    "cpu_share": robot.cpu_share, "memory_mb": robot.memory_mb, "elsewhere": False}
                   for robot in robots]
        # Recorded robots this process's farm does not run: the local farm's robots of another web process.
        + [{"name": name, "owner": owner, "scene": scene, "host": "another process", "node": "", "address": address,
            "restarted": False, "cpu_share": None, "memory_mb": None, "elsewhere": True}
           for name, owner, scene, address in sorted(records) if address and name not in {r.name for r in robots}],
    }


def status_lines(farm: RobotFarm, sessions: Callable[[], Session]) -> list[str]:
    """The farm's capacity, its hosts, and one line per robot with its owner, host and load."""
    status = farm_status(farm, sessions)
    capacity = status["capacity"]
    lines = [f"farm: {status['backend']}, {capacity['hosts']} host(s), {capacity['running']} of {capacity['robots']} "
             f"robots running ({capacity['free']} free)"]
    for host in status["hosts"]:
        cpus = "" if host["cpus"] is None else f"{host['cpus']:g} CPUs, "
        lines.append(f"  host {host['host']} node {host['node_id'][:12]}: {cpus}{host['robots']} robot(s)")
    lines.append(f"{'robot':24} {'owner':16} {'host':16} {'node':12} {'cpu':>6} {'memory':>8}  address")
    for robot in status["robots"]:
        cpu = "-" if robot["cpu_share"] is None else f"{robot['cpu_share'] * 100:.0f}%"
        memory = "-" if robot["memory_mb"] is None else f"{robot['memory_mb']:.0f}MB"
        restarted = "  (restarted)" if robot["restarted"] else ""
        lines.append(f"{robot['name']:24} {robot['owner'] or '-':16} {robot['host']:16} {robot['node'][:12]:12} "
                     f"{cpu:>6} {memory:>8}  {robot['address']}{restarted}")
    if not status["robots"]:
        lines.append("  (no robot runs on the farm)")
    return lines
