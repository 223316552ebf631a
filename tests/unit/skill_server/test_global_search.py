"""The whole-map search answers only when one place clearly fits: in a bare rectangular room a panorama fits
two places (the room turned by 180 degrees), and it must say so instead of picking one."""

from __future__ import annotations

import math

import numpy as np

from skill_server.sim.geometry import Pose2D
from skill_server.sim.scenes import BoxObstacle, SceneSpec, get_scene, room_walls
from skill_server.skills.environment_model import EnvironmentModel
from skill_server.skills.global_search import (
    COARSE_SIGMA_M,
    COARSE_STEP_M,
    COARSE_STEP_RAD,
    STEP_LOOKUPS,
    CoarseScores,
    FieldLookup,
    SlicedSearch,
    _scores,
    search,
)
from skill_server.skills.scan_matching import distance_field

HALF_X, HALF_Y = 4.0, 3.0
FIELD_CAP_CELLS = 12


def lookup_of(scene: SceneSpec) -> tuple[FieldLookup, np.ndarray]:
    model = EnvironmentModel()
    model.add_floor_plan(scene)
    occupied = model.occupied()
    field = np.where(occupied, 0.5 - distance_field(~occupied, FIELD_CAP_CELLS),
                     distance_field(occupied, FIELD_CAP_CELLS) - 0.5) * model.resolution_m
    return FieldLookup(field, model.origin_m, model.resolution_m), model.log_odds < 0


def panorama_in(lookup: FieldLookup, at: Pose2D) -> np.ndarray:
    """Echoes of a full turn at pose at, in its own frame, marched along each ray on the map."""
    points = []
    for bearing in np.radians(np.arange(0.0, 360.0, 3.0)):
        world = at.theta_rad + bearing
        steps = np.arange(0.05, 8.0, 0.01)
        xs, ys = at.x_m + steps * math.cos(world), at.y_m + steps * math.sin(world)
        hit = np.argmax(lookup.at(xs, ys) <= 0.0)
        if hit:
            points.append((steps[hit] * math.cos(bearing), steps[hit] * math.sin(bearing)))
    return np.array(points)


def test_a_bare_room_fits_two_places_and_the_search_says_so() -> None:
    bare = SceneSpec(name="bare", floor_half_x_m=HALF_X, floor_half_y_m=HALF_Y, boxes=tuple(room_walls(HALF_X, HALF_Y)))
    lookup, free = lookup_of(bare)
    found = search(lookup, free, panorama_in(lookup, Pose2D(1.3, 0.7, 0.4)))
    assert found.anchor_pose is None and found.places >= 2, found


def test_one_piece_of_furniture_tells_the_places_apart() -> None:
    furnished = SceneSpec(name="furnished", floor_half_x_m=HALF_X, floor_half_y_m=HALF_Y,
                          boxes=(*room_walls(HALF_X, HALF_Y),
                                 BoxObstacle("crate", 2.5, 1.4, 0.3, 0.3, 0.5, (0.6, 0.4, 0.2, 1.0))))
    lookup, free = lookup_of(furnished)
    truth = Pose2D(1.3, 0.7, 0.4)
    found = search(lookup, free, panorama_in(lookup, truth))
    assert found.anchor_pose is not None, found
    assert found.anchor_pose.distance_to(truth) < 0.1
    assert abs(math.remainder(found.anchor_pose.theta_rad - truth.theta_rad, 2 * math.pi)) < math.radians(3)


def test_the_sliced_search_answers_as_the_whole_search_in_bounded_slices() -> None:
    """The world's loop runs the search a slice per filter update: the same answer as at once, no slice doing more
    than STEP_LOOKUPS point lookups (two to four headings of the coarse search), the coarse scores equal to the plain
    ones. At once, the lab's search held the loop for 0.35-0.7 s of CPU (seconds on a loaded host)."""
    lab = get_scene("lab")
    lookup, free = lookup_of(lab)
    points = panorama_in(lookup, Pose2D(-1.0, 1.5, 2.0))
    whole = search(lookup, free, points)
    sliced = SlicedSearch(lookup, free, points)
    answer = sliced.step()
    while answer is None:
        answer = sliced.step()
    assert answer == whole and whole.anchor_pose is not None
    positions = lookup.free_positions(free, COARSE_STEP_M)
    headings = len(np.arange(-math.pi, math.pi, COARSE_STEP_RAD))
    per_slice = max(1, STEP_LOOKUPS // (len(positions) * len(points)))
    assert per_slice * len(positions) * len(points) <= STEP_LOOKUPS
    assert sliced.steps_taken >= math.ceil(headings / per_slice) >= 20
    coarse = CoarseScores(lookup, points, positions)
    for theta in np.radians([-177.0, -33.0, 0.0, 58.0, 121.0]):
        assert np.array_equal(coarse.at(float(theta)), _scores(lookup, points, positions, float(theta),
                                                               COARSE_SIGMA_M))
