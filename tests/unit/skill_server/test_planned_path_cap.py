"""A goal's planned path is capped where feedback is made (skill server) and again where it leaves for the page."""

from __future__ import annotations

from middleware.robots.messages import feedback_dict
from protos.telelab.v1 import robot_pb2
from skill_server.goals import PLANNED_PATH_POINTS, capped_path


def test_a_long_path_is_thinned_evenly_keeping_its_start_and_the_goal() -> None:
    path = tuple((0.01 * i, -0.02 * i) for i in range(300))
    capped = capped_path(path)
    assert len(capped) == PLANNED_PATH_POINTS == 64
    assert capped[0] == path[0] and capped[-1] == path[-1]
    indices = [path.index(point) for point in capped]
    assert indices == sorted(set(indices)), "points repeat or go backwards"
    steps = [b - a for a, b in zip(indices, indices[1:], strict=False)]
    assert max(steps) - min(steps) <= 1, f"not even: {steps}"


def test_a_short_path_is_kept_as_it_is() -> None:
    for length in (0, 1, 2, 64):
        path = tuple((float(i), 0.0) for i in range(length))
        assert capped_path(path) == path


def test_the_page_gets_at_most_64_points_whatever_a_robot_sends() -> None:
    feedback = robot_pb2.GoalFeedback(planned_path=[robot_pb2.Pose2D(x_m=i, y_m=1.0) for i in range(100)])
    shown = feedback_dict(feedback)["planned_path"]
    assert len(shown) == 64 and shown[0] == [0.0, 1.0] and shown[-1] == [63.0, 1.0]
