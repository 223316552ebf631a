"""Would sticky routing of a robot's channels to one web worker save upstream streams? Without it, every worker that
has a viewer of a robot opens its own camera and telemetry streams from the robot's skill server and unpacks every
frame once; with it (nginx hashing the robot's name to a worker), one worker does. Measured here: the skill server's
CPU and each web worker's CPU while 1, 2 or 3 worker processes each relay one robot's camera and telemetry to one
viewer. The floor is the same robot with one worker relaying (what sticky routing would give for any number of
workers).

    python -m benchmarks.sticky [--quick] [--output DIR]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import sys
import time
from pathlib import Path

from benchmarks.report import Measurement, print_table, write_json

WORKER_COUNTS = (1, 2, 3)


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def relay(address: str, ready, stop, received) -> None:
    """One web worker's share: the robot's camera and telemetry hubs with one viewer each, read until stop."""
    from middleware.robots.link import RobotLink

    link = RobotLink("robot", address)
    viewers = [link.camera.subscribe(), link.telemetry.subscribe()]
    count = 0
    ready.set()
    while not stop.is_set():
        for viewer in viewers:
            if viewer.next_message(0.05) is not None:
                count += 1
    received.value = count
    for viewer in viewers:
        viewer.close()
    link.close()


def measure(address: str, robot_pid: int, workers: int, window_s: float, settle_s: float) -> dict[str, float]:
    """CPU shares (of one core) of the robot and of the workers while `workers` processes relay its streams."""
    # New processes, not forks of this one (its threads and channels): forks of a fork server that imported the
    # relay's code once. Spawned, each of the six relays spent about 2 s of CPU importing the middleware.
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["middleware.robots.link"])
    stop = context.Event()
    readies = [context.Event() for _ in range(workers)]
    counts = [context.Value("i", 0) for _ in range(workers)]
    processes = [context.Process(target=relay, args=(address, readies[i], stop, counts[i]), daemon=True)
                 for i in range(workers)]
    for process in processes:
        process.start()
    for ready in readies:
        if not ready.wait(60):
            raise RuntimeError("a relaying worker did not start")
    time.sleep(settle_s)  # the streams are open and flowing
    pids = [process.pid for process in processes if process.pid is not None]
    robot_before, workers_before = _cpu_s(robot_pid), [_cpu_s(pid) for pid in pids]
    started = time.perf_counter()
    time.sleep(window_s)
    elapsed = time.perf_counter() - started
    robot_share = (_cpu_s(robot_pid) - robot_before) / elapsed
    worker_shares = [(_cpu_s(pid) - before) / elapsed for pid, before in zip(pids, workers_before, strict=True)]
    stop.set()
    for process in processes:
        process.join(10)
    return {"robot": robot_share, "workers": sum(worker_shares), "per_worker": sum(worker_shares) / workers,
            "messages": float(sum(count.value for count in counts))}


def run(quick: bool, output: Path) -> list[Measurement]:
    from middleware.robots.processes import SkillServerProcess

    window_s, settle_s = (0.5, 0.5) if quick else (15.0, 1.0)
    robot = SkillServerProcess("sticky", "lab", echo=False)
    robot.serve()
    try:
        assert robot.process is not None
        measured = {workers: measure(robot.address, robot.process.pid, workers, window_s, settle_s)
                    for workers in WORKER_COUNTS}
    finally:
        robot.stop()
    sticky = measured[1]
    load = os.getloadavg()[0]
    rows = []
    for workers in WORKER_COUNTS[1:]:
        spread = measured[workers]
        scenario = f"one robot watched on {workers} workers (floor: sticky, 1 worker)"
        rows += [
            Measurement(scenario, "skill server CPU (share of one core)", spread["robot"], "cores", "-",
                        floor=sticky["robot"], note=f"load average {load:.1f}"),
            Measurement(scenario, "web workers' CPU for this robot, together", spread["workers"], "cores", "-",
                        floor=sticky["workers"]),
            Measurement(scenario, "extra CPU without sticky routing", spread["robot"] + spread["workers"]
                        - sticky["robot"] - sticky["workers"], "cores", "-"),
        ]
    print_table("Sticky routing: one robot's streams relayed by 1, 2 or 3 web workers", rows)
    output.mkdir(parents=True, exist_ok=True)
    write_json(output / "sticky.json", rows, {"quick": quick, "window_s": window_s,
                                              "measured": {str(k): v for k, v in measured.items()}})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--output", default="bench-results")
    args = parser.parse_args(argv)
    run(args.quick, Path(args.output))
    return 0


if __name__ == "__main__":
    sys.exit(main())
