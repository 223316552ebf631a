"""A whole-map search that does not answer says so in the goal's feedback, not only in its events.

The kidnapping exercise's browser test once read a localization goal that had been "searching" for 90 s with an
empty message and a tight cloud on a wrong pose: nothing in the goal told whether the panorama was still too short
to search, whether the searches ended with several places fitting, or with too few points on the map. The
feedback's figures now carry the last search's answer (searches, places_fitting, search_inliers) and the
panorama's sweep and travel, so a reader of the goal (a student's code, a test's diagnosis) sees which half failed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skill_server.sequencer import attach_sequencer
from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import World
from skill_server.skills import relocalization
from skill_server.skills.global_search import SearchResult
from skill_server.skills.relocalization import SEARCH_AFTER_UPDATES, Relocalizer

TOKEN = "t"
EXERCISE_START = Pose2D(2.9, -0.2, 2.5)  # the kidnapping exercise's practice start; odometry believes the dock


def answering(result: SearchResult) -> type:
    """A stand-in for the whole-map search, sliced in the robot, that answers result in its first slice."""

    class Answering:
        def __init__(self, *_args: object, **_kwargs: object) -> None:
            pass

        def step(self) -> SearchResult:
            return result

    return Answering


def test_a_search_that_finds_two_places_says_so_in_the_figures(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(relocalization, "SlicedSearch", answering(SearchResult(None, 0.93, 2)))
    relocalizer = Relocalizer(0.5)
    assert relocalizer.figures["searches"] == 0
    angles = np.linspace(-2.0, 2.0, 30)
    for step in range(21):  # a 1 m drive: a panorama ready to search
        relocalizer.gather(Pose2D(0.05 * step, 0.0, 0.0), np.full(30, 2.0), angles, 8.0)
    for _ in range(SEARCH_AFTER_UPDATES):
        said = relocalizer.after_update(None, None, Pose2D(1.0, 0.0, 0.0), Pose2D())  # type: ignore[arg-type]
    assert "2 places" in said.announcement
    figures = relocalizer.figures
    assert (figures["searches"], figures["places_fitting"]) == (1, 2)
    assert figures["search_inliers"] == pytest.approx(0.93)
    assert figures["panorama_travelled_m"] == pytest.approx(1.0)


@pytest.mark.parametrize(("turns", "gathered_again"), [(1.0, False), (3.5, True)])
def test_a_panorama_that_fits_no_place_after_three_turns_is_gathered_again(monkeypatch: pytest.MonkeyPatch,
                                                                           turns: float, gathered_again: bool) -> None:
    """The exercise's browser journey once searched 23 times in 90 s of turning, the panorama grown to 53.7 rad and
    52 % of it on the map at the best place: smeared by odometry's drift, it could never answer."""
    monkeypatch.setattr(relocalization, "SlicedSearch", answering(SearchResult(None, 0.52, 1)))
    relocalizer = Relocalizer(0.5)
    angles = np.linspace(-2.0, 2.0, 30)
    scans = 200
    for step in range(scans + 1):  # turning on the spot
        relocalizer.gather(Pose2D(0.0, 0.0, turns * 2 * math.pi * step / scans), np.full(30, 2.0), angles, 8.0)
    for _ in range(SEARCH_AFTER_UPDATES):
        said = relocalizer.after_update(None, None, Pose2D(), Pose2D())  # type: ignore[arg-type]
    assert relocalizer.figures["searches"] == 1
    swept = relocalizer.figures["panorama_swept_rad"]
    if gathered_again:
        assert swept == 0 and "gathering them again" in said.announcement
    else:
        assert swept == pytest.approx(turns * 2 * math.pi) and "keep turning" in said.announcement


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_after_the_exercises_kidnapping_turning_localizes_and_the_feedback_tells_the_search(seed: int) -> None:
    with World("lab", realtime=False, seed=seed, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        world.step_for(0.5)
        world.set_pose(EXERCISE_START, kidnap=True)
        sequencer.activate(TOKEN, "environment_modelling", {"use_floor_plan": True, "restart": True}, False)
        goal_id = sequencer.activate(TOKEN, "localization", {}, False).goal.goal_id
        swept: list[float] = []
        estimate = None
        for sequence in range(1, int(40 * 40)):  # 40 s of turning at 0.6 rad/s at most
            world.drive(TOKEN, sequence, 0.0, 0.6)
            world.step_for(world.tick_dt_s)
            feedback = dict(sequencer.goals.get(goal_id).snapshot().feedback.values)  # type: ignore[union-attr]
            swept.append(feedback["panorama_swept_rad"])
            estimate = sequencer.perception.published_estimate
            if estimate is not None and estimate.converged:
                break
        truth = world.snapshot.ground_truth
        assert estimate is not None and estimate.converged, f"not localized in 40 s: {feedback}"
        assert estimate.pose.distance_to(truth) < 0.3
        # The panorama grew while it searched (300 degrees before the search), and the search that answered is
        # counted with its one place.
        assert max(swept) >= math.radians(300.0) * 0.95
        assert feedback["searches"] >= 1 and feedback["places_fitting"] == 1
