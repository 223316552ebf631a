"""Builds and runs a skill server: the World, the Robot service, health checking and reflection."""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from concurrent import futures
from dataclasses import dataclass
from types import FrameType

import grpc
from grpc_health.v1 import health, health_pb2, health_pb2_grpc
from grpc_reflection.v1alpha import reflection

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.errors import RobotError
from skill_server.process import CONTROLLER_TOKEN_VARIABLE, RESTARTS_VARIABLE, ProcessWatch, exec_again
from skill_server.robot import BatterySpec, Robot
from skill_server.sequencer import Sequencer
from skill_server.service import RobotService
from skill_server.sim.world import World

ROBOT_SERVICE_NAME = robot_pb2.DESCRIPTOR.services_by_name["Robot"].full_name  # "telelab.v1.Robot"
MAX_WORKERS = 64  # every open stream holds a worker thread
STOP_GRACE_S = 1.0


@dataclass
class SkillServer:
    """A running skill server; unpacks as (server, port, world) and stops with stop()."""

    server: grpc.Server
    port: int
    robot: Robot
    health: health.HealthServicer
    host: str
    _health_pool: futures.ThreadPoolExecutor

    @property
    def world(self) -> World:
        """The robot's world (tests place the robot and read its snapshots)."""
        return self.robot.world

    @property
    def sequencer(self) -> Sequencer:
        """The robot's sequencer."""
        return self.robot.sequencer

    @property
    def robot_name(self) -> str:
        """The name the robot answers to in GetRobotInfo."""
        return self.robot.name

    @property
    def scene(self) -> str:
        """The scene's name."""
        return self.robot.world.scene.name

    def __iter__(self) -> Iterator[object]:
        return iter((self.server, self.port, self.world))

    @property
    def address(self) -> str:
        """host:port, as a gRPC channel target."""
        return f"{self.host}:{self.port}"

    def stop(self, grace_s: float = STOP_GRACE_S) -> None:
        """Says NOT_SERVING, ends the streams by stopping the world, then stops gRPC within grace_s."""
        self.health.enter_graceful_shutdown()
        self.robot.stop()
        self.server.stop(grace_s).wait()
        self._health_pool.shutdown(wait=False)

    def wait(self) -> None:
        """Blocks until the gRPC server has stopped."""
        self.server.wait_for_termination()


def create_server(
    port: int = 0,
    scene: str = "lab",
    realtime: bool = True,
    seed: int = 0,
    deadman_timeout_s: float = 0.4,
    robot_name: str = "lab-1",
    host: str = "127.0.0.1",
    controller_token: str = "",
    battery: BatterySpec | None = None,
    process: ProcessWatch | None = None,
) -> SkillServer:
    """Builds the world and the gRPC server, starts both, and returns them (port=0 picks a free port).

    controller_token names the controller from the start: a robot restarted by its farm keeps obeying its
    owner without anyone handing the token over again.
    """
    robot = Robot.build(scene, name=robot_name, seed=seed, realtime=realtime, deadman_timeout_s=deadman_timeout_s,
                        battery=battery)
    if controller_token:
        robot.set_controller(controller_token)
    server = grpc.server(futures.ThreadPoolExecutor(max_workers=MAX_WORKERS, thread_name_prefix="robot-rpc"))
    if process is not None:
        robot.process = process
    robot_pb2_grpc.add_RobotServicer_to_server(RobotService(robot), server)
    health_pool = futures.ThreadPoolExecutor(max_workers=2, thread_name_prefix="robot-health")
    health_servicer = health.HealthServicer(experimental_non_blocking=True, experimental_thread_pool=health_pool)
    health_pb2_grpc.add_HealthServicer_to_server(health_servicer, server)
    reflection.enable_server_reflection((ROBOT_SERVICE_NAME, health.SERVICE_NAME, reflection.SERVICE_NAME), server)
    bound_port = server.add_insecure_port(f"{host}:{port}")
    if bound_port == 0:
        robot.stop()
        raise OSError(f"could not listen on {host}:{port}")
    robot.start()
    server.start()
    for service in ("", ROBOT_SERVICE_NAME):
        health_servicer.set(service, health_pb2.HealthCheckResponse.SERVING)
    return SkillServer(server, bound_port, robot, health_servicer, host, health_pool)


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """The command line of `python -m skill_server` (and of `telelab skill-server`)."""
    parser = argparse.ArgumentParser(prog="python -m skill_server", description="Runs one robot's skill server.")
    parser.add_argument("--port", type=int, required=True, help="TCP port (0 picks a free one)")
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    parser.add_argument("--scene", default="lab", help="scene name (default lab)")
    parser.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    parser.add_argument("--fast", action="store_true", help="step as fast as possible instead of in real time")
    parser.add_argument("--deadman-s", type=float, default=0.4, help="deadman timeout in sim seconds (default 0.4)")
    parser.add_argument("--name", default="lab-1", help="robot name (default lab-1)")
    parser.add_argument("--battery-drive-s", type=float, default=BatterySpec.full_drive_s,
                        help="seconds a full battery lasts driving at top speed "
                             f"(default {BatterySpec.full_drive_s:g})")
    parser.add_argument("--parent-pid", type=int, default=0,
                        help="stop when this process is no longer the parent (a farm's actor that died)")
    return parser.parse_args(argv)




def main(argv: Sequence[str] | None = None) -> int:
    """Runs a skill server until SIGINT or SIGTERM."""
    args = parse_args(argv)
    stop_requested = threading.Event()
    restart_requested = threading.Event()

    def restart() -> None:
        restart_requested.set()
        stop_requested.set()

    restarts = int(os.environ.get(RESTARTS_VARIABLE, "0") or 0)
    try:
        running = create_server(
            port=args.port,
            scene=args.scene,
            realtime=not args.fast,
            seed=args.seed,
            deadman_timeout_s=args.deadman_s,
            robot_name=args.name,
            host=args.host,
            controller_token=os.environ.get(CONTROLLER_TOKEN_VARIABLE, ""),
            battery=BatterySpec(full_drive_s=args.battery_drive_s),
            process=ProcessWatch(restart, restarts),
        )
    except (RobotError, OSError) as error:
        print(f"skill server: {error}", file=sys.stderr, flush=True)
        return 2

    def request_stop(signum: int, frame: FrameType | None) -> None:
        stop_requested.set()

    signal.signal(signal.SIGINT, request_stop)
    signal.signal(signal.SIGTERM, request_stop)
    print(
        f"skill server {args.name} listening on {args.host}:{running.port} (scene {running.scene})",
        flush=True,
    )
    logging.getLogger(__name__).info("%s listening on %s:%d (scene %s, restart %d)", args.name, args.host,
                                     running.port, running.scene, restarts)
    while not stop_requested.wait(0.5):
        if args.parent_pid and os.getppid() != args.parent_pid:
            break
    controller_token = running.robot.world.controller_token
    running.stop()
    if restart_requested.is_set():
        exec_again(_arguments_again(args, running.port), controller_token, restarts + 1)
    return 0


def _arguments_again(args: argparse.Namespace, port: int) -> list[str]:
    """The command line that starts this robot again as it runs now (on the port it holds, not 0)."""
    again = ["--port", str(port), "--host", args.host, "--scene", args.scene, "--seed", str(args.seed),
             "--deadman-s", repr(args.deadman_s), "--name", args.name, "--battery-drive-s", repr(args.battery_drive_s)]
    if args.fast:
        again.append("--fast")
    if args.parent_pid:
        again += ["--parent-pid", str(args.parent_pid)]
    return again
