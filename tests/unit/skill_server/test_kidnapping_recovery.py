"""After a kidnapping, what the robot drew while it was lost must not outlive the search: the environment model keeps
the floor plan (the search's scans were drawn over the dock odometry believed in, and localization converged there),
the obstacle grid holds no echo away from a real surface once the robot is found (go_to_goal found no path through
them), and the navigation stack's pose tracking, lost meanwhile, takes the place found over when the localization skill
stops."""

from __future__ import annotations

import numpy as np
import pytest

from skill_server.sequencer import Sequencer, attach_sequencer
from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import World
from skill_server.skills.environment_model import EnvironmentModel
from skill_server.skills.perception import LocalizationEstimate
from skill_server.skills.scan_matching import distance_field

TOKEN = "t"
START = Pose2D(-1.0, 1.5, 2.0)  # beside the cabinet, 1.8 m from the dock odometry still believes in


def kidnapped_and_searching(world: World, carried_to: Pose2D) -> tuple[Sequencer, str]:
    """The robot carried to carried_to without being told, then the kidnapping exercise's search: environment
    modelling from the floor plan and localization with no guess."""
    sequencer = attach_sequencer(world)
    world.set_controller(TOKEN)
    world.step_for(0.5)
    world.set_pose(carried_to, kidnap=True)
    sequencer.activate(TOKEN, "environment_modelling", {"use_floor_plan": True, "restart": True}, False)
    return sequencer, sequencer.activate(TOKEN, "localization", {}, False).goal.goal_id


def turn_until_localized(world: World, sequencer: Sequencer, sources: set[str | None]) -> LocalizationEstimate | None:
    """Turns on the spot until the localization converges; sources gathers what the skills steered by meanwhile."""
    estimate = None
    for sequence in range(1, 800):
        world.drive(TOKEN, sequence, 0.0, 0.6)
        world.step_for(world.tick_dt_s)
        estimate = sequencer.perception.published_estimate
        if estimate is not None and estimate.converged:
            break
        navigation = sequencer.perception.navigation
        sources.add(navigation.source if navigation is not None else None)
    return estimate


def floor_plan_kept(world: World, sequencer: Sequencer) -> EnvironmentModel:
    """The floor plan as built, once the environment model was checked to hold it still."""
    plan = EnvironmentModel()
    plan.add_floor_plan(world.scene)
    model = sequencer.perception.environment
    assert model is not None
    flipped = int(np.count_nonzero(model.occupied() != plan.occupied()))
    assert flipped < 20, f"{flipped} cells of the floor plan changed while the robot was lost"
    return plan


def test_a_kidnapped_robot_found_again_keeps_the_map_drops_the_lost_echoes_and_tracks_on() -> None:
    with World("lab", realtime=False, seed=2, deadman_timeout_s=1000.0) as world:
        sequencer, localization = kidnapped_and_searching(world, START)
        estimate = turn_until_localized(world, sequencer, set())
        world.drive(TOKEN, 1000, 0.0, 0.0)
        world.step_for(1.0)
        truth = world.snapshot.ground_truth
        assert estimate is not None and estimate.converged and estimate.pose.distance_to(truth) < 0.15

        plan = floor_plan_kept(world, sequencer)

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


def test_a_robot_carried_to_the_mirror_of_where_it_stood_is_not_tracked_there_while_it_searches() -> None:
    # The room is a rectangle: seen from the place it was carried to, the walls fit the place odometry believes in,
    # turned half a turn, as well. The pose tracking restarted there converged on it and the map drew the search there.
    carried_to = Pose2D(2.77, -0.19, -2.92)
    believed = Pose2D(-2.77, 0.19, carried_to.theta_rad + np.pi)
    with World("lab", realtime=False, seed=6, deadman_timeout_s=1000.0) as world:
        world.set_pose(believed)
        sequencer, _ = kidnapped_and_searching(world, carried_to)
        sources: set[str | None] = set()
        estimate = turn_until_localized(world, sequencer, sources)
        assert sources == {"odometry"}, f"steered by {sources} while the localization searched"
        assert estimate is not None and estimate.pose.distance_to(world.snapshot.ground_truth) < 0.15
        floor_plan_kept(world, sequencer)


# Half a turn round the room's centre from each start, the room fits as well, inside the default guess (the dock,
# 0.5 m). Seed 11, 1 m from the mirror: the guess's check looked at headings near the guess's only. Seed 40, 1.8 m
# from it: the check looked within 1.5 m of the estimate, not at every place the guess allows.
@pytest.mark.parametrize(("seed", "carried_to"), [(11, Pose2D(-0.38, 0.36, 2.67)),
                                                  (40, Pose2D(0.6897, 0.5802, 2.7399))])
def test_a_robot_carried_near_the_dock_is_found_where_it_stands_not_at_its_mirror_place(
        seed: int, carried_to: Pose2D) -> None:
    with World("lab", realtime=False, seed=seed, deadman_timeout_s=1000.0) as world:
        sequencer, _ = kidnapped_and_searching(world, carried_to)
        estimate = turn_until_localized(world, sequencer, set())
        truth = world.snapshot.ground_truth
        assert estimate is not None and estimate.converged
        assert estimate.pose.distance_to(truth) < 0.15, f"converged at {estimate.pose}, the robot stands at {truth}"
