"""The whole-map search places coarsely. Beside an obstacle, a cloud started at the true pose fitted every echo but
was not yet confirmed; the search then found "one place" 9 cm off, the cloud restarted there, converged and stayed
9 cm off, and the round trip that followed reported "reached" 10 cm from its start. Where the search finds the
estimate's own place, the estimate is confirmed and the cloud kept; elsewhere, the cloud restarts there.

The search itself is stubbed here (its answer is the input of this rule); tests/unit/skill_server/test_global_search.py
and test_localization_evidence.py run the real one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skill_server.sim.geometry import Pose2D
from skill_server.skills import relocalization
from skill_server.skills.global_search import SearchResult
from skill_server.skills.relocalization import SEARCH_AFTER_UPDATES, Relocalizer

ESTIMATE = Pose2D(1.0, 0.5, 0.3)


def searched(monkeypatch: pytest.MonkeyPatch, found_anchor: Pose2D) -> relocalization.Step:
    """A relocalizer past its guess, with a panorama of a 1 m drive, and a search answering found_anchor."""
    answer = SearchResult(found_anchor, 0.97, 1)

    class AnsweredAtOnce:  # the whole-map search, sliced in the robot, answers in its first slice here
        def __init__(self, *_args: object, **_kwargs: object) -> None:
            pass

        def step(self) -> SearchResult:
            return answer

    monkeypatch.setattr(relocalization, "search", lambda *_args, **_kwargs: answer)
    monkeypatch.setattr(relocalization, "SlicedSearch", AnsweredAtOnce)
    relocalizer = Relocalizer(0.02)
    angles = np.linspace(-2.0, 2.0, 30)
    for step in range(21):  # the odometry's frame equals the map's here: the anchor is (0, 0, 0)
        relocalizer.gather(Pose2D(0.05 * step, 0.0, 0.0), np.full(30, 2.0), angles, 8.0)
    for _ in range(SEARCH_AFTER_UPDATES - 1):
        assert relocalizer.after_update(None, None, Pose2D(1.0, 0.0, 0.0), ESTIMATE).found is None  # type: ignore[arg-type]
    return relocalizer.after_update(None, None, Pose2D(1.0, 0.0, 0.0), ESTIMATE)  # type: ignore[arg-type]


def test_a_search_that_finds_the_estimate_s_own_place_keeps_the_cloud(monkeypatch: pytest.MonkeyPatch) -> None:
    # The estimate puts the panorama's anchor (the odometry 1 m back) at (1 - cos 0.3, 0.5 - sin 0.3, 0.3) on the
    # map; the search finds it 8.5 cm and half a degree from there.
    anchor = Pose2D(1.0 - math.cos(0.3), 0.5 - math.sin(0.3), 0.3)
    step = searched(monkeypatch, Pose2D(anchor.x_m + 0.06, anchor.y_m + 0.06, 0.31))
    assert step.found is None
    assert "the estimate's" in step.announcement


def test_a_search_that_finds_another_place_restarts_the_cloud_there(monkeypatch: pytest.MonkeyPatch) -> None:
    step = searched(monkeypatch, Pose2D(-1.5, 2.0, 2.0))
    assert step.found is not None
    assert step.found.distance_to(ESTIMATE) > 1.0
    assert "checking it" in step.announcement
