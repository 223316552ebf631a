"""After a kidnapping, what the robot drew while it was lost must not outlive the search: the environment model keeps
the floor plan (the search's scans were drawn over the dock odometry believed in, and localization converged there),
the obstacle grid holds no echo away from a real surface once the robot is found (go_to_goal found no path through
them), and the navigation stack's pose tracking takes the place found over when the localization skill stops."""

from __future__ import annotations

import numpy as np

from skill_server.sequencer import attach_sequencer
from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import World
from skill_server.skills.environment_model import EnvironmentModel
from skill_server.skills.scan_matching import distance_field

TOKEN = "t"
START = Pose2D(-1.0, 1.5, 2.0)  # beside the cabinet, 1.8 m from the dock odometry still believes in


def test_a_kidnapped_robot_found_again_keeps_the_map_drops_the_lost_echoes_and_tracks_on() -> None:
    with World("lab", realtime=False, seed=2, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        world.step_for(0.5)
        world.set_pose(START, kidnap=True)
        sequencer.activate(TOKEN, "environment_modelling", {"use_floor_plan": True, "restart": True}, False)
        localization = sequencer.activate(TOKEN, "localization", {}, False).goal.goal_id
        for sequence in range(1, 800):
            world.drive(TOKEN, sequence, 0.0, 0.6)
            world.step_for(world.tick_dt_s)
            estimate = sequencer.perception.published_estimate
            if estimate is not None and estimate.converged:
                break
        world.drive(TOKEN, 1000, 0.0, 0.0)
        world.step_for(1.0)
        truth = world.snapshot.ground_truth
        assert estimate is not None and estimate.converged and estimate.pose.distance_to(truth) < 0.15

        plan = EnvironmentModel()
        plan.add_floor_plan(world.scene)
        model = sequencer.perception.environment
        assert model is not None
        flipped = int(np.count_nonzero(model.occupied() != plan.occupied()))
        assert flipped < 20, f"{flipped} cells of the floor plan changed while the robot was lost"

        grid = sequencer.perception.obstacles
        surfaces = np.zeros_like(grid.occupied())
        size = plan.size  # the floor plan's cells (5 cm, origin -6 m) onto the grid's (5 cm, origin -10 m)
        shift = int(round((plan.origin_m - grid.origin_m) / grid.resolution_m))
        surfaces[shift:shift + size, shift:shift + size] = plan.occupied()
        gap_cells = distance_field(surfaces, 10)
        stray = grid.occupied() & (gap_cells > 3)  # echoes 15 cm or more from every wall and obstacle
        assert not stray.any(), f"{int(stray.sum())} echoes of the obstacle grid lie away from every surface"

        sequencer.cancel(TOKEN, localization)
        world.step_for(1.0)
        navigation = sequencer.perception.navigation
        assert navigation is not None and navigation.source == "map tracking"
        assert navigation.pose.distance_to(world.snapshot.ground_truth) < 0.15
