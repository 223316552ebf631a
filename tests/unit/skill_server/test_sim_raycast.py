"""The closed-form ray caster the sensors use agrees with pybullet's own ray test."""

from __future__ import annotations

import math

import numpy as np

from skill_server.sim.geometry import Pose2D
from skill_server.sim.raycast import StaticSceneCaster
from skill_server.sim.world import World


def _free_poses(world: World, count: int, seed: int) -> list[Pose2D]:
    """Random poses in the lab whose body touches nothing."""
    boxes = world.describe().scene_boxes
    rng = np.random.default_rng(seed)
    poses: list[Pose2D] = []
    while len(poses) < count:
        x, y = rng.uniform(-3.7, 3.7), rng.uniform(-2.7, 2.7)
        gap_m = min(math.hypot(max(abs(x - b.center_x_m) - b.half_x_m, 0.0), max(abs(y - b.center_y_m) - b.half_y_m,
                                                                              0.0)) for b in boxes)
        if gap_m > world.spec.body_radius_m + 0.02:
            poses.append(Pose2D(float(x), float(y), float(rng.uniform(-math.pi, math.pi))))
    return poses


def test_sonar_and_laser_rays_hit_where_pybullet_says() -> None:
    with World("lab", realtime=False) as world:
        caster = StaticSceneCaster(world.scene)
        gaps_m = []
        for pose in _free_poses(world, 25, seed=3):
            sonar_from, sonar_to = world._sonar.rays(pose)
            laser_from, laser_to = world._laser.rays(pose)
            starts, ends = np.vstack([sonar_from, laser_from]), np.vstack([sonar_to, laser_to])
            lengths_m = np.linalg.norm(ends - starts, axis=1)
            gaps_m.append((caster.cast(starts, ends) - world.cast_rays(starts, ends)) * lengths_m)
        gaps = np.abs(np.concatenate(gaps_m))
        # pybullet's round pillar is about a millimetre fatter, so a few grazing rays differ; the rest agree.
        assert np.mean(gaps < 0.005) > 0.99
        assert np.median(gaps) < 0.001


def test_a_ray_above_a_low_box_or_away_from_it_hits_nothing() -> None:
    with World("lab", realtime=False) as world:
        caster = StaticSceneCaster(world.scene)
        # The bench (-1.0, -2.0) is 0.45 m high: a ray at 0.2 m hits its north face, one at 0.6 m passes over.
        starts = np.array([[-1.0, -1.0, 0.2], [-1.0, -1.0, 0.6], [0.0, 0.0, 0.2]])
        ends = np.array([[-1.0, -2.0, 0.2], [-1.0, -2.0, 0.6], [0.5, 0.0, 0.2]])
        fractions = caster.cast(starts, ends)
        assert math.isclose(fractions[0], 0.75, abs_tol=1e-9)
        assert fractions[1] == 1.0 and fractions[2] == 1.0


def test_localization_on_the_floor_plan_converges_from_a_guess_half_a_metre_off() -> None:
    from skill_server.sequencer import attach_sequencer

    with World("lab", realtime=False, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller("token")
        sequencer.activate("token", "environment_modelling", {"use_floor_plan": True, "restart": True}, False)
        world.step_for(0.2)
        assert sequencer.perception.environment.occupied()[int((4.05 + 6.0) / 0.05), 120]  # the east wall
        sequencer.activate("token", "localization", {"initial_x_m": 0.35, "initial_y_m": -0.35}, False)
        sequencer.activate("token", "direct_control", {"linear_mps": 0.0, "angular_radps": 0.8, "duration_s": 8.0},
                           False)
        world.step_for(10.0)
        estimate = sequencer.perception.published_estimate
        assert estimate is not None and estimate.converged
        assert world.snapshot.ground_truth.distance_to(estimate.pose) < 0.08
