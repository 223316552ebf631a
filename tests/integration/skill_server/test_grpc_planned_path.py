"""Go-to-goal's feedback carries the path still ahead over real gRPC (fast mode), as the consoles' maps draw it:
waypoints in the lab frame from the pose the skill believes, ending at the goal, never more than 64."""

from __future__ import annotations

import math

import pytest

from middleware.robots.messages import feedback_dict
from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from tests.integration.skill_server.test_grpc_goals import (
    DEADLINE_S,
    activate,
    controlled,  # noqa: F401 - the fixture, asked for below
)


def test_go_to_goal_feedback_carries_the_path_ahead_ending_at_the_goal(request: pytest.FixtureRequest) -> None:
    robot: robot_pb2_grpc.RobotStub = request.getfixturevalue("controlled")  # a fresh robot under our token
    goal_xy = (1.0, 0.4)
    goal = activate(robot, "go_to_goal", goal_x_m=goal_xy[0], goal_y_m=goal_xy[1]).goal
    updates = list(robot.WatchGoal(robot_pb2.WatchGoalRequest(goal_id=goal.goal_id), timeout=DEADLINE_S))
    assert updates[-1].state.status == robot_pb2.GOAL_STATUS_SUCCEEDED
    feedback = [u.feedback for u in updates if u.WhichOneof("update") == "feedback" and u.feedback.state == "driving"]
    assert feedback, "no feedback while driving"
    for each in feedback:
        path = [(p.x_m, p.y_m) for p in each.planned_path]
        assert 1 <= len(path) <= 64
        assert path[-1] == pytest.approx(goal_xy), "the path does not end at the goal"
        assert all(math.isfinite(x) and math.isfinite(y) for x, y in path)
        # Ahead of the pose the skill steers by: no waypoint farther from the goal than that pose is, by much.
        start_m = math.dist((each.pose.x_m, each.pose.y_m), goal_xy)
        assert all(math.dist(point, goal_xy) <= start_m + 0.5 for point in path)
    # As the page receives it: pairs of numbers.
    shown = feedback_dict(feedback[0])["planned_path"]
    assert shown == [[p.x_m, p.y_m] for p in feedback[0].planned_path]
    # The count the feedback always had agrees with the points carried.
    assert feedback[0].values["waypoints"] == len(feedback[0].planned_path)
