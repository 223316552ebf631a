"""The plan executor on a real skill server (fast mode, gRPC on loopback, in this process): plan step -> skill
started (p50, p99), beside ActivateSkill -> accepted as its floor; and the time per step of a plan against the
same skills called one by one with ActivateSkill and followed to their end with WatchGoal (what a client-side
runner would do), as a ratio in the same run, with the sim time the steps need as the floor.

    python -m benchmarks.plans [--quick] [--output DIR]

Each step is direct_control turning in place for 0.1 s (6 ticks), alternately left and right, so the robot
stays where it is and every step costs the same sim time. The skill-started times come from the sequencer's
plan observer: when the executor began a skill line, and when the skill's controller had been built through
the registry and ticked once.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import grpc

from benchmarks.report import Measurement, percentile_ms, print_table, write_json
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.plans.executor import SkillStepTiming
from skill_server.server import SkillServer, create_server

TOKEN = "plans-benchmark"
STEP_S = 0.1
DEADLINE_S = 120.0


def _turn(direction: float) -> dict[str, robot_pb2.ParameterValue]:
    return {"linear_mps": robot_pb2.ParameterValue(double_value=0.0),
            "angular_radps": robot_pb2.ParameterValue(double_value=0.5 * direction),
            "duration_s": robot_pb2.ParameterValue(double_value=STEP_S)}


def _plan(rounds: int) -> robot_pb2.PlanBlock:
    """repeat rounds { turn left 0.1 s; turn right 0.1 s }: 2 x rounds skill steps."""
    body = [robot_pb2.PlanStep(line=2 + i, column=3, skill=robot_pb2.SkillStep(skill="direct_control",
                                                                                parameters=_turn(sign)))
            for i, sign in enumerate((1.0, -1.0))]
    return robot_pb2.PlanBlock(steps=[robot_pb2.PlanStep(line=1, column=1, repeat=robot_pb2.RepeatStep(
        count=rounds, body=robot_pb2.PlanBlock(steps=body)))])


def _wait_for_end(robot: robot_pb2_grpc.RobotStub, goal_id: str) -> robot_pb2.GoalState:
    final = None
    for update in robot.WatchGoal(robot_pb2.WatchGoalRequest(goal_id=goal_id), timeout=DEADLINE_S):
        if update.WhichOneof("update") == "state":
            final = update.state
    assert final is not None and final.status == robot_pb2.GOAL_STATUS_SUCCEEDED, final
    return final


def run_plan(server: SkillServer, robot: robot_pb2_grpc.RobotStub, rounds: int) -> tuple[float, list[float]]:
    """Wall time of a plan of 2 x rounds steps, and each step's start -> skill started [s]."""
    timings: list[SkillStepTiming] = []
    server.sequencer.plan_observer = timings.append
    started = time.perf_counter()
    goal = robot.RunPlan(robot_pb2.RunPlanRequest(token=TOKEN, name="bench", plan=_plan(rounds)),
                         timeout=DEADLINE_S).goal
    _wait_for_end(robot, goal.goal_id)
    elapsed = time.perf_counter() - started
    server.sequencer.plan_observer = None
    assert len(timings) == 2 * rounds, f"{len(timings)} skill lines observed of {2 * rounds}"
    return elapsed, [t.skill_started_s - t.step_started_s for t in timings]


def run_direct(robot: robot_pb2_grpc.RobotStub, steps: int) -> tuple[float, list[float]]:
    """Wall time of the same steps by ActivateSkill, each followed to its end; each ActivateSkill -> accepted."""
    accepted: list[float] = []
    started = time.perf_counter()
    for index in range(steps):
        asked = time.perf_counter()
        goal = robot.ActivateSkill(robot_pb2.ActivateSkillRequest(
            token=TOKEN, skill="direct_control", parameters=_turn(1.0 if index % 2 == 0 else -1.0)),
            timeout=DEADLINE_S).goal
        accepted.append(time.perf_counter() - asked)
        _wait_for_end(robot, goal.goal_id)
    return time.perf_counter() - started, accepted


def seconds_per_tick(server: SkillServer, window_s: float) -> float:
    """The idle loop's wall time per tick in fast mode (the floor every step's sim time costs)."""
    first = server.world.snapshot
    time.sleep(window_s)
    last = server.world.snapshot
    return window_s / max(1, last.tick - first.tick)


def run(quick: bool, output: Path) -> list[Measurement]:
    rounds = 10 if quick else 250  # 2 steps a round
    server = create_server(port=0, realtime=False, deadman_timeout_s=2.0, robot_name="bench-plans")
    channel = grpc.insecure_channel(server.address)
    try:
        robot = robot_pb2_grpc.RobotStub(channel)
        robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
        run_plan(server, robot, 2)  # warm: the first plan and goal pay for imports and the first streams
        run_direct(robot, 2)
        tick_s = seconds_per_tick(server, 0.3 if quick else 2.0)
        plan_s, started = run_plan(server, robot, rounds)
        direct_s, accepted = run_direct(robot, 2 * rounds)
    finally:
        channel.close()
        server.stop(grace_s=0.5)
    steps = 2 * rounds
    ticks_per_step = math.ceil(STEP_S / server.world.tick_dt_s - 1e-9) + 1
    floor_ms = ticks_per_step * tick_s * 1000.0
    plan_ms, direct_ms = plan_s / steps * 1000.0, direct_s / steps * 1000.0
    tick_ms = server.world.tick_dt_s * 1000.0
    grade = not quick
    p50, p99 = percentile_ms(started, 50), percentile_ms(started, 99)
    scenario = f"{steps} steps of direct_control {STEP_S:g} s"
    rows = [
        Measurement("plan step -> skill started", "p50", p50, "ms", "-", floor=percentile_ms(accepted, 50),
                    note="floor: ActivateSkill -> accepted over gRPC"),
        Measurement("plan step -> skill started", "p99", p99, "ms", f"<= {tick_ms:.1f} (one tick)",
                    floor=percentile_ms(accepted, 99), passed=(p99 <= tick_ms) if grade else None,
                    note="floor: ActivateSkill -> accepted over gRPC"),
        Measurement(scenario, "time per step, plan", plan_ms, "ms", "-", floor=floor_ms,
                    note=f"floor: the {ticks_per_step} ticks a step needs at the idle loop's rate"),
        Measurement(scenario, "time per step, ActivateSkill + WatchGoal", direct_ms, "ms", "-", floor=floor_ms),
        Measurement(scenario, "plan / direct, time per step", plan_ms / direct_ms, "ratio", "<= 1",
                    passed=(plan_ms <= direct_ms) if grade else None),
        Measurement(scenario, "plan / direct, overhead above the floor",
                    (plan_ms - floor_ms) / (direct_ms - floor_ms) if direct_ms > floor_ms else None,
                    "ratio", "-", note="the plan's time above the ticks its steps need, over ActivateSkill's"),
    ]
    print_table("Plans: the executor on the skill server against ActivateSkill from a client", rows)
    write_json(output / "plans.json", rows, {
        "quick": quick, "steps": steps,
        "measured": {"plan_total_s": plan_s, "direct_total_s": direct_s, "seconds_per_idle_tick": tick_s,
                     "ticks_per_step": ticks_per_step, "step_started_ms": [s * 1000.0 for s in started],
                     "activate_accepted_ms": [s * 1000.0 for s in accepted]}})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a short smoke run that grades nothing")
    parser.add_argument("--output", default="bench-results")
    args = parser.parse_args(argv)
    run(args.quick, Path(args.output))
    return 0


if __name__ == "__main__":
    sys.exit(main())
