"""The exercises' robot API over a simulated robot with its skills (the skill server's sequencer), stepped as fast
as it computes: run_skill and start_skill reach the robot's real skills, localization() reads the lab's real
localization estimate, and the robot can be carried somewhere without being told (a kidnapping)."""

from __future__ import annotations

from typing import Any

from skill_server.errors import RobotError
from skill_server.sequencer import Sequencer, attach_sequencer
from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import World
from tests.integration.exercises.world_backend import TOKEN, WorldBackend, run_program


class SkillBackend(WorldBackend):
    """WorldBackend with the robot's skills: goals run in the same stepped world."""

    def __init__(self, world: World, sequencer: Sequencer, time_limit_s: float, telemetry_hz: float = 0.0,
                 latency_s: float = 0.0) -> None:
        self.sequencer = sequencer
        self.ended: list[Any] = []  # the goals run_skill waited for, as they ended
        super().__init__(world, time_limit_s, telemetry_hz, latency_s)

    def send(self, linear_mps: float, angular_radps: float) -> None:
        super().send(linear_mps, angular_radps)
        self.sequencer.preempt_motor_goal_for_drive(self.world.drive_version)  # as the robot's Drive does

    def skill(self, name: str, parameters: dict[str, Any], wait: bool = True) -> str:
        try:
            goal_id = self.sequencer.activate(TOKEN, name, parameters, preempt=True).goal.goal_id
        except RobotError:
            return "REFUSED"
        goal = self.sequencer.goals.get(goal_id)
        assert goal is not None
        while wait and not goal.status.is_terminal and self.now() < self.time_limit_s:
            self.wait_until(self.now() + self.world.tick_dt_s)
        if goal.status.is_terminal:
            self.ended.append(goal.snapshot())
        return goal.status.name if goal.status.is_terminal else "EXECUTING"

    def _reading(self) -> dict[str, Any]:
        reading = super()._reading()
        estimate = self.sequencer.perception.published_estimate
        if estimate is not None:
            pose = estimate.pose_at(self.world.snapshot.odometry.pose)
            reading["localization"] = {"converged": estimate.converged, "std_x_m": estimate.std_x_m,
                                       "std_y_m": estimate.std_y_m, "std_theta_rad": estimate.std_theta_rad,
                                       "estimate": {"x_m": pose.x_m, "y_m": pose.y_m, "theta_rad": pose.theta_rad}}
        return reading


def run_with_skills(code: str, scene: str, start: list[float], time_limit_s: float, seed: int,
                    kidnap: bool = False, telemetry_hz: float = 0.0, latency_s: float = 0.0) -> SkillBackend:
    """Runs code against a robot with its skills from start (kidnap: carried there from its dock without being
    told, as the kidnapping exercise places it)."""
    with World(scene, realtime=False, seed=seed, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        world.step_for(0.5)
        world.set_pose(Pose2D(*start), kidnap=kidnap)
        backend = SkillBackend(world, sequencer, time_limit_s, telemetry_hz, latency_s)
        run_program(code, backend)
        return backend
