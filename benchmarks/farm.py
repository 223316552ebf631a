"""The robot farm: how fast a class's robots start, what each costs, and the Ray farm's overhead.

Run `python -m benchmarks.farm [--quick] [--output DIR]`: prints a table, writes DIR/farm.json.

For each backend (local child processes; Ray, as a one-machine cluster on 127.0.0.1 started here), the
same steps:
- one robot started alone: the floor of every start figure;
- a class start: N robots of the lab scene requested at once (one thread per student, as N students pressing
  "Start" together) -> the time until each one answers SERVING (p50, max), for N = 10, 20, 30;
- with the N robots running headless, driven (each in a slow circle, commands at 5 Hz as a console sends them)
  and watched (each robot's pose stream, StreamTelemetry with pose_only at 30 Hz: the server's side of a view
  rendered in the browser, one frame per pose; the server renders no camera), over a 10 s window: each robot's
  real-time factor (simulated seconds per wall second, read from its telemetry), its CPU share (its processes'
  CPU time, /proc) and resident memory. Targets: real-time factor >= 0.95 for every robot while the farm admits
  them; CPU share per robot <= the share Ray placement declares
  (middleware/farm/costs.py);
- then left alone: each robot parks (no physics steps; sensors at 4 Hz): its CPU share over 10 s (target <= 1 %
  of a core), and the wake time of one robot, a drive command -> its telemetry showing it move (target <= 200 ms).
The Ray rows are then divided by the local ones (start time, memory per robot): the farm's overhead.
Last, on the local farm, 100 idle robots at once: their CPU share each and in all, their memory, and the slowest
real-time factor (the issue's >= 100 idle robots beside a class).
"""

from __future__ import annotations

import argparse
import contextlib
import statistics
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import grpc

from benchmarks.report import Measurement, print_table, write_json
from middleware.farm.base import RobotFarm, RobotSpec
from middleware.farm.costs import host_cores, robot_cpu_share
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc

SCENE = "lab"
WINDOW_S = 10.0  # driven and watched
PARKED_WINDOW_S = 10.0
SETTLE_S = 5.0  # the watchers' streams flowing
PARK_SETTLE_S = 5.0  # they park a second after the last command
PARKED_CPU_TARGET = 0.01
WAKE_TARGET_S = 0.2
IDLE_CROWD = 100
WATCH_HZ = 30.0


def sim_clock(address: str) -> tuple[float, float]:
    """(simulated seconds, wall seconds) of the robot now, from the first message of its telemetry."""
    with grpc.insecure_channel(address) as channel:
        stream = robot_pb2_grpc.RobotStub(channel).StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=1),
                                                                   timeout=10)
        message = next(iter(stream))
        stream.cancel()
    return message.sim_time_s, time.monotonic()


def token_of(index: int) -> str:
    return f"token-{index}"


def start_class(farm: RobotFarm, prefix: str, count: int) -> list[float]:
    """Starts count robots at once; the seconds each took to serve."""
    barrier = threading.Barrier(count)

    def one(index: int) -> float:
        barrier.wait()
        started = time.monotonic()
        farm.start(RobotSpec(f"{prefix}-{index}", SCENE, token_of(index)))
        return time.monotonic() - started

    with ThreadPoolExecutor(count) as pool:
        return list(pool.map(one, range(count)))


class Drivers:
    """Drives every robot in a slow circle, a command per robot every 0.2 s (under the 0.4 s deadman), and watches
    each through its telemetry at watch_hz (0: not watched), as its student's browser-rendered view would."""

    def __init__(self, addresses: dict[str, str], tokens: dict[str, str], watch_hz: float = WATCH_HZ) -> None:
        self._channels = {name: grpc.insecure_channel(address) for name, address in addresses.items()}
        self._tokens = tokens
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._streams: list[Any] = []
        self._watchers = [threading.Thread(target=self._watch, args=(channel, watch_hz), daemon=True)
                          for channel in self._channels.values()] if watch_hz > 0 else []
        self.poses_seen = 0

    def __enter__(self) -> Drivers:
        self._thread.start()
        for watcher in self._watchers:
            watcher.start()
        return self

    def __exit__(self, *_exc: object) -> None:
        self._stop.set()
        self._thread.join()
        for stream in list(self._streams):
            stream.cancel()
        for watcher in self._watchers:
            watcher.join(5)
        for name, channel in self._channels.items():
            with contextlib.suppress(grpc.RpcError):
                robot_pb2_grpc.RobotStub(channel).Drive(robot_pb2.DriveCommand(
                    token=self._tokens[name], sequence=10**9, linear_mps=0.0, angular_radps=0.0), timeout=2)
            channel.close()

    def _watch(self, channel: grpc.Channel, rate_hz: float) -> None:
        stream = robot_pb2_grpc.RobotStub(channel).StreamTelemetry(
            robot_pb2.StreamTelemetryRequest(rate_hz=rate_hz, pose_only=True))
        self._streams.append(stream)
        with contextlib.suppress(grpc.RpcError):
            for _message in stream:
                self.poses_seen += 1
                if self._stop.is_set():
                    break

    def _run(self) -> None:
        sequence = 0
        while not self._stop.wait(0.2):
            sequence += 1
            for name, channel in self._channels.items():
                with contextlib.suppress(grpc.RpcError):
                    robot_pb2_grpc.RobotStub(channel).Drive(robot_pb2.DriveCommand(
                        token=self._tokens[name], sequence=sequence, linear_mps=0.1, angular_radps=0.3), timeout=2)


def measure_running(farm: RobotFarm, names: list[str], window_s: float) -> dict[str, list[float]]:
    """Real-time factor, CPU share and memory of each running robot over window_s."""
    addresses = {robot.name: robot.address for robot in farm.robots() if robot.name in names}
    before = {name: sim_clock(address) for name, address in addresses.items()}
    farm.robots()  # the first look of the CPU meters
    time.sleep(window_s)
    robots = [robot for robot in farm.robots() if robot.name in names]
    after = {name: sim_clock(address) for name, address in addresses.items()}
    factors = [(after[n][0] - before[n][0]) / (after[n][1] - before[n][1]) for n in addresses]
    return {"real_time_factor": factors,
            "cpu_share": [r.cpu_share for r in robots if r.cpu_share is not None],
            "memory_mb": [r.memory_mb for r in robots if r.memory_mb is not None]}


def wake_time_s(address: str, token: str) -> float:
    """A parked robot: seconds from a drive command to its telemetry showing it move."""
    with grpc.insecure_channel(address) as channel:
        stub = robot_pb2_grpc.RobotStub(channel)
        stream = stub.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=50), timeout=10)
        messages = iter(stream)
        next(messages)
        sent = time.monotonic()
        stub.Drive(robot_pb2.DriveCommand(token=token, sequence=2 * 10**9, linear_mps=0.2, angular_radps=0.0),
                   timeout=2)
        for message in messages:
            if message.odometry.linear_mps > 0.001:
                break
        woke = time.monotonic() - sent
        stream.cancel()
        stub.Drive(robot_pb2.DriveCommand(token=token, sequence=2 * 10**9 + 1), timeout=2)
    return woke


def measure_backend(backend: str, make: Callable[[], RobotFarm], counts: list[int], quick: bool
                    ) -> tuple[list[Measurement], dict[str, Any]]:
    farm = make()
    rows: list[Measurement] = []
    detail: dict[str, Any] = {}
    try:
        started = time.monotonic()
        farm.start(RobotSpec(f"{backend}-alone", SCENE))
        alone_s = time.monotonic() - started
        farm.stop(f"{backend}-alone")
        rows.append(Measurement(f"farm start ({backend})", "one robot alone", alone_s, "s", "-"))
        for count in counts:
            prefix = f"{backend}-{count}"
            durations = start_class(farm, prefix, count)
            names = [f"{prefix}-{i}" for i in range(count)]
            addresses = {robot.name: robot.address for robot in farm.robots()}
            with Drivers({name: addresses[name] for name in names},
                         {n: token_of(i) for i, n in enumerate(names)}) as drivers:
                time.sleep(SETTLE_S)
                seen_before, watched_from = drivers.poses_seen, time.monotonic()
                driven = measure_running(farm, names, WINDOW_S)
                pose_hz = (drivers.poses_seen - seen_before) / (time.monotonic() - watched_from) / count
            time.sleep(PARK_SETTLE_S)
            parked = measure_running(farm, names, PARKED_WINDOW_S)
            wakes = [wake_time_s(addresses[names[i]], token_of(i)) for i in range(min(count, 5))]
            for robot in farm.robots():
                farm.stop(robot.name)
            scenario = f"class of {count} ({backend})"
            worst_factor = min(driven["real_time_factor"])
            share, parked_share = statistics.mean(driven["cpu_share"]), statistics.mean(parked["cpu_share"])
            rows += [
                Measurement(scenario, "start until SERVING p50", statistics.median(durations), "s", "-", alone_s),
                Measurement(scenario, "start until SERVING max", max(durations), "s", "-", alone_s),
                Measurement(scenario, "real-time factor, slowest driven and watched robot", worst_factor, "x",
                            ">= 0.95", 1.0, None if quick else worst_factor >= 0.95),
                Measurement(scenario, "poses received per watched robot", pose_hz, "Hz", f">= {WATCH_HZ * 0.9:g}",
                            WATCH_HZ, None if quick else pose_hz >= WATCH_HZ * 0.9),
                Measurement(scenario, "CPU share per driven and watched robot, mean", share, "core",
                            f"<= {robot_cpu_share()}", robot_cpu_share(),
                            None if quick else share <= robot_cpu_share()),
                Measurement(scenario, "CPU share per parked robot, mean", parked_share, "core", "<= 0.01",
                            PARKED_CPU_TARGET, None if quick else parked_share <= PARKED_CPU_TARGET),
                Measurement(scenario, "wake: drive -> moving, max of 5", max(wakes), "s", "<= 0.2", WAKE_TARGET_S,
                            None if quick else max(wakes) <= WAKE_TARGET_S),
                Measurement(scenario, "memory per robot, mean", statistics.mean(driven["memory_mb"]), "MB", "-"),
            ]
            detail[scenario] = {"start_s": durations, "driven": driven, "parked": parked, "wake_s": wakes,
                                "poses_hz_per_robot": pose_hz}
    finally:
        for robot in farm.robots():
            farm.stop(robot.name)
        farm.close()
    return rows, detail


def measure_idle_crowd(count: int, quick: bool) -> tuple[list[Measurement], dict[str, Any]]:
    """count robots on the local farm, started 8 at a time and left alone: their cost once parked."""
    from middleware.farm.local import LocalProcessFarm

    farm = LocalProcessFarm(capacity=count)
    try:
        with ThreadPoolExecutor(8) as pool:
            list(pool.map(lambda i: farm.start(RobotSpec(f"idle-{i}", SCENE, token_of(i))), range(count)))
        time.sleep(PARK_SETTLE_S)
        parked = measure_running(farm, [f"idle-{i}" for i in range(count)], PARKED_WINDOW_S)
    finally:
        farm.close()
    scenario = f"{count} idle robots (local)"
    total = sum(parked["cpu_share"])
    worst = min(parked["real_time_factor"])
    return [
        Measurement(scenario, "CPU share per robot, mean", statistics.mean(parked["cpu_share"]), "core", "<= 0.01",
                    PARKED_CPU_TARGET, None if quick else statistics.mean(parked["cpu_share"]) <= PARKED_CPU_TARGET),
        Measurement(scenario, "CPU of them all", total, "cores", "-"),
        Measurement(scenario, "real-time factor, slowest robot", worst, "x", ">= 0.95", 1.0,
                    None if quick else worst >= 0.95),
        Measurement(scenario, "memory per robot, mean", statistics.mean(parked["memory_mb"]), "MB", "-"),
    ], {scenario: parked}


def overhead_rows(rows: list[Measurement], counts: list[int]) -> list[Measurement]:
    """Ray's figures divided by the local farm's, for the same class size."""
    def figure(scenario: str, name: str) -> float | None:
        return next((r.measured for r in rows if r.scenario == scenario and r.figure == name), None)

    ratios = []
    for count in counts:
        for name in ("start until SERVING max", "CPU share per driven and watched robot, mean",
                     "memory per robot, mean"):
            ray_value, local_value = figure(f"class of {count} (ray)", name), figure(f"class of {count} (local)", name)
            if ray_value is not None and local_value:
                ratios.append(Measurement(f"Ray overhead, class of {count}", name + " ray/local",
                                          ray_value / local_value, "x", "-", 1.0))
    return ratios


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.farm", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="a short smoke run that grades nothing")
    parser.add_argument("--output", type=Path, default=Path("bench-results"))
    parser.add_argument("--backends", default="local,ray", help="comma-separated: local, ray")
    args = parser.parse_args(argv)
    counts = [2] if args.quick else [10, 20, 30]
    if args.quick:  # a smoke run: every step once, in windows too short to grade (it grades nothing)
        global WINDOW_S, PARKED_WINDOW_S, SETTLE_S, PARK_SETTLE_S
        # A parked robot's CPU is a clock tick (10 ms) in about 3 s: a shorter window would often read 0.
        WINDOW_S, PARKED_WINDOW_S, SETTLE_S, PARK_SETTLE_S = 1.0, 3.0, 1.0, 2.0
    began = time.monotonic()
    rows: list[Measurement] = []
    detail: dict[str, Any] = {}
    backends = [name.strip() for name in args.backends.split(",") if name.strip()]
    if "local" in backends:
        from middleware.farm.local import LocalProcessFarm

        made, more = measure_backend("local", lambda: LocalProcessFarm(capacity=max(counts)), counts, args.quick)
        rows += made
        detail.update(more)
    if "ray" in backends:
        from middleware.farm.ray_farm import RayFarm, start_local_cluster

        address = start_local_cluster()
        made, more = measure_backend("ray", lambda: RayFarm(address), counts, args.quick)
        rows += made + overhead_rows(rows + made, counts)
        detail.update(more)
    if "local" in backends:
        made, more = measure_idle_crowd(4 if args.quick else IDLE_CROWD, args.quick)
        rows += made
        detail.update(more)
    print_table(f"robot farm on {host_cores()} cores: class start, cost per robot, Ray's overhead", rows)
    elapsed = time.monotonic() - began
    print(f"\n({'quick' if args.quick else 'full'} run, {elapsed:.0f} s)")
    write_json(args.output / "farm.json", rows, {"quick": args.quick, "elapsed_s": elapsed, "counts": counts,
                                                 "scene": SCENE, "window_s": WINDOW_S,
                                                 "parked_window_s": PARKED_WINDOW_S, "detail": detail})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
