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
import os
import sys
import time
from dataclasses import dataclass
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
    """repeat rounds / 50 { repeat 50 { turn left 0.1 s; turn right 0.1 s } }: 2 x rounds skill steps (a repeat
    counts to 100 at most)."""
    inner = min(rounds, 50)
    body = [robot_pb2.PlanStep(line=3 + i, column=5, skill=robot_pb2.SkillStep(skill="direct_control",
                                                                                parameters=_turn(sign)))
            for i, sign in enumerate((1.0, -1.0))]
    turns = robot_pb2.PlanStep(line=2, column=3, repeat=robot_pb2.RepeatStep(
        count=inner, body=robot_pb2.PlanBlock(steps=body)))
    return robot_pb2.PlanBlock(steps=[robot_pb2.PlanStep(line=1, column=1, repeat=robot_pb2.RepeatStep(
        count=rounds // inner, body=robot_pb2.PlanBlock(steps=[turns])))])


def _wait_for_end(robot: robot_pb2_grpc.RobotStub, goal_id: str) -> robot_pb2.GoalState:
    final = None
    for update in robot.WatchGoal(robot_pb2.WatchGoalRequest(goal_id=goal_id), timeout=DEADLINE_S):
        if update.WhichOneof("update") == "state":
            final = update.state
    assert final is not None and final.status == robot_pb2.GOAL_STATUS_SUCCEEDED, final
    return final


@dataclass(frozen=True)
class Run:
    """One way of running the steps: its wall time, the sim time and ticks the loop ran meanwhile, and per-step
    samples [s]."""

    steps: int
    wall_s: float
    sim_s: float
    ticks: int
    samples_s: list[float]

    @property
    def wall_ms_per_step(self) -> float:
        return self.wall_s / self.steps * 1000.0

    @property
    def sim_ms_per_step(self) -> float:
        return self.sim_s / self.steps * 1000.0


class _Clock:
    """Wall time, sim time and ticks across a run (fast mode: the loop ticks as fast as it can all along)."""

    def __init__(self, server: SkillServer) -> None:
        self._server = server
        self._wall_s, snapshot = time.perf_counter(), server.world.snapshot
        self._sim_s, self._tick = snapshot.sim_time_s, snapshot.tick

    def run(self, steps: int, samples_s: list[float]) -> Run:
        snapshot = self._server.world.snapshot
        return Run(steps, time.perf_counter() - self._wall_s, snapshot.sim_time_s - self._sim_s,
                   snapshot.tick - self._tick, samples_s)


def run_plan(server: SkillServer, robot: robot_pb2_grpc.RobotStub, rounds: int) -> Run:
    """A plan of 2 x rounds steps, with each step's start -> skill started."""
    timings: list[SkillStepTiming] = []
    server.sequencer.plan_observer = timings.append
    clock = _Clock(server)
    goal = robot.RunPlan(robot_pb2.RunPlanRequest(token=TOKEN, name="bench", plan=_plan(rounds)),
                         timeout=DEADLINE_S).goal
    _wait_for_end(robot, goal.goal_id)
    run = clock.run(2 * rounds, [t.skill_started_s - t.step_started_s for t in timings])
    server.sequencer.plan_observer = None
    assert len(timings) == 2 * rounds, f"{len(timings)} skill lines observed of {2 * rounds}"
    return run


def run_direct(server: SkillServer, robot: robot_pb2_grpc.RobotStub, steps: int) -> Run:
    """The same steps by ActivateSkill, each followed to its end, with each ActivateSkill -> accepted."""
    accepted: list[float] = []
    clock = _Clock(server)
    for index in range(steps):
        asked = time.perf_counter()
        goal = robot.ActivateSkill(robot_pb2.ActivateSkillRequest(
            token=TOKEN, skill="direct_control", parameters=_turn(1.0 if index % 2 == 0 else -1.0)),
            timeout=DEADLINE_S).goal
        accepted.append(time.perf_counter() - asked)
        _wait_for_end(robot, goal.goal_id)
    return clock.run(steps, accepted)


def run(quick: bool, output: Path) -> list[Measurement]:
    rounds = 10 if quick else 250  # 2 steps a round
    server = create_server(port=0, realtime=False, deadman_timeout_s=2.0, robot_name="bench-plans")
    channel = grpc.insecure_channel(server.address)
    try:
        robot = robot_pb2_grpc.RobotStub(channel)
        robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
        run_plan(server, robot, 2)  # warm: the first plan and goal pay for imports and the first streams
        run_direct(server, robot, 2)
        plan = run_plan(server, robot, rounds)
        direct = run_direct(server, robot, 2 * rounds)
    finally:
        channel.close()
        server.stop(grace_s=0.5)
    tick_s = server.world.tick_dt_s
    ticks_per_step = round(STEP_S / tick_s)  # the sim time a step asks for, in ticks: its floor
    step_sim_ms = ticks_per_step * tick_s * 1000.0
    # The wall floor: the ticks a step needs, at the rate the loop ticked during the plan's own run.
    wall_floor_ms = ticks_per_step * plan.wall_s / max(1, plan.ticks) * 1000.0
    grade = not quick
    started, accepted = plan.samples_s, direct.samples_s
    p50, p99 = percentile_ms(started, 50), percentile_ms(started, 99)
    scenario = f"{plan.steps} steps of direct_control {STEP_S:g} s"
    over_plan, over_direct = plan.sim_ms_per_step - step_sim_ms, direct.sim_ms_per_step - step_sim_ms
    rows = [
        Measurement("plan step -> skill started", "p50", p50, "ms", "-", floor=percentile_ms(accepted, 50),
                    note="floor: ActivateSkill -> accepted over gRPC"),
        Measurement("plan step -> skill started", "p99", p99, "ms", f"<= {tick_s * 1000:.1f} (one tick)",
                    floor=percentile_ms(accepted, 99), passed=(p99 <= tick_s * 1000) if grade else None,
                    note="floor: ActivateSkill -> accepted over gRPC"),
        Measurement(scenario, "sim time per step, plan", plan.sim_ms_per_step, "ms", "-", floor=step_sim_ms,
                    note=f"floor: the {ticks_per_step} ticks a step needs"),
        Measurement(scenario, "sim time per step, ActivateSkill + WatchGoal", direct.sim_ms_per_step, "ms", "-",
                    floor=step_sim_ms, note="fast mode: the loop ticks on while the client calls"),
        Measurement(scenario, "wall time per step, plan", plan.wall_ms_per_step, "ms", "-", floor=wall_floor_ms,
                    note="floor: those ticks at the loop's rate during the run"),
        Measurement(scenario, "wall time per step, ActivateSkill + WatchGoal", direct.wall_ms_per_step, "ms", "-",
                    floor=wall_floor_ms),
        Measurement(scenario, "plan / direct, wall time per step", plan.wall_ms_per_step / direct.wall_ms_per_step,
                    "ratio", "<= 1", passed=(plan.wall_ms_per_step <= direct.wall_ms_per_step) if grade else None),
        Measurement(scenario, "plan / direct, overhead per step in sim time",
                    over_plan / over_direct if over_direct > 0 else None, "ratio", "-",
                    note=f"overhead above the step's own ticks: plan {over_plan:.1f} ms, direct {over_direct:.1f} ms"),
    ]
    print_table("Plans: the executor on the skill server against ActivateSkill from a client", rows)
    write_json(output / "plans.json", rows, {
        "quick": quick, "steps": plan.steps, "load_average_1m": os.getloadavg()[0],
        "measured": {"plan": {"wall_s": plan.wall_s, "sim_s": plan.sim_s, "ticks": plan.ticks},
                     "direct": {"wall_s": direct.wall_s, "sim_s": direct.sim_s, "ticks": direct.ticks},
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
