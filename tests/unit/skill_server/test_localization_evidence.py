"""Localization says "converged" only when the scan supports the pose: after driving, a guess of (0, 0, 0) far from
the robot collapsed the cloud onto a wrong pose (0.9-3.2 m and 43-145 degrees off) and called it converged, and
the map then took scans at that pose. The true pose as the guess still converges at once; a wrong one is given up
for a search of the whole map with the scans of the turn, which finds the true pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skill_server.sequencer import attach_sequencer
from skill_server.sim.world import World


def drive_somewhere(sequencer, world, seed: int) -> None:
    """Six turns and straight runs, as a student drives before thinking of localizing."""
    rng = np.random.default_rng(seed)
    for _ in range(6):
        sequencer.activate("t", "direct_control", {"linear_mps": 0.0, "angular_radps": float(rng.uniform(-1, 1)),
                                                   "duration_s": 1.5}, True)
        world.step_for(1.6)
        sequencer.activate("t", "direct_control", {"linear_mps": 0.25, "angular_radps": 0.0, "duration_s": 2.0}, True)
        world.step_for(2.1)


def localize_while_turning(seed: int, guess_is_truth: bool) -> list[tuple[bool, float, float]]:
    """(converged, position error [m], heading error [deg]) every 0.2 s of 13 s turning in place: the search starts
    after 300 degrees (8.7 s) and is spread over about 2.5 s of filter updates (a slice each)."""
    with World("lab", realtime=False, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller("t")
        sequencer.activate("t", "environment_modelling", {"use_floor_plan": True, "restart": True}, False)
        world.step_for(0.2)
        drive_somewhere(sequencer, world, seed)
        truth = world.snapshot.ground_truth
        guess = (truth.x_m, truth.y_m, truth.theta_rad) if guess_is_truth else (0.0, 0.0, 0.0)
        sequencer.activate("t", "localization", {"initial_x_m": guess[0], "initial_y_m": guess[1],
                                                 "initial_theta_rad": guess[2]}, False)
        turn = {"linear_mps": 0.0, "angular_radps": 0.6, "duration_s": 10.0}
        sequencer.activate("t", "direct_control", turn, True)
        samples = []
        for sample in range(65):
            if sample == 49:  # direct control lasts 10 s at most: the turn goes on
                sequencer.activate("t", "direct_control", turn, True)
            world.step_for(0.2)
            estimate = sequencer.perception.published_estimate
            if estimate is None:
                continue
            truth = world.snapshot.ground_truth
            heading = abs(math.degrees(math.remainder(truth.theta_rad - estimate.pose.theta_rad, 2 * math.pi)))
            samples.append((estimate.converged, truth.distance_to(estimate.pose), heading))
        return samples


@pytest.mark.parametrize("seed", [0, 1, 3])
def test_a_wrong_guess_after_driving_never_claims_a_wrong_pose_and_the_search_finds_the_true_one(seed: int) -> None:
    samples = localize_while_turning(seed, guess_is_truth=False)
    wrong = [(round(error, 2), round(heading)) for converged, error, heading in samples
             if converged and (error > 0.25 or heading > 20)]
    assert not wrong, f"converged while {wrong[0][0]} m and {wrong[0][1]} degrees off"
    assert samples[-1][0], "the search of the whole map did not find the pose within 13 s of turning"


def test_the_true_pose_as_the_guess_converges_within_a_second_and_stays_close() -> None:
    samples = localize_while_turning(0, guess_is_truth=True)
    assert samples[4][0], "not converged after a second"
    assert all(converged and error < 0.1 and heading < 5 for converged, error, heading in samples[4:])
