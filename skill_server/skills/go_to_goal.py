"""The go_to_goal skill: plan around seen obstacles, follow the path, stop within the maximum error."""

from __future__ import annotations

import math
from dataclasses import replace

from skill_server.goals import EventKind, GoalFeedback, capped_path
from skill_server.schema import ParameterSchema, ParameterType, SkillDescription
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import (
    Outcome,
    SkillController,
    TickInput,
    aborted,
    bearing_to,
    feedback_for,
    heading_error,
    succeeded,
)
from skill_server.skills.obstacles import ObstacleMap, clearance
from skill_server.skills.planner import nearest_reachable_point, path_is_blocked, plan_path

GO_TO_GOAL = "go_to_goal"
LOOKAHEAD_M = 0.35
REPLAN_PERIOD_S = 3.0  # a blocked path replans at once; this only refines it as the grid fills in
STOP_CLEARANCE_M = 0.06  # never drive forward with less than this between the rim and an echo
UNREACHABLE_AFTER_S = 2.0  # a goal blocked or without a path for this long is given up
STUCK_AFTER_S = 4.0  # blocked ahead with no way around for this long: COLLISION_AHEAD
COORD_LIMIT_M = 50.0
STOP_FRACTION = 0.3


def go_to_goal_description(spec: RobotSpec) -> SkillDescription:
    """The schema of go_to_goal."""
    return SkillDescription(
        name=GO_TO_GOAL,
        title="Go to goal",
        help=(
            "Drive to a point of the lab, going around the obstacles the laser and sonars detect on the way. "
            "Ends when the robot is within the maximum error of the goal; deactivating reports the distance left."
        ),
        parameters=(
            ParameterSchema("goal_x_m", ParameterType.DOUBLE, "m", -COORD_LIMIT_M, COORD_LIMIT_M, 1.0,
                            "Goal x in the lab frame (the start pose's frame)."),
            ParameterSchema("goal_y_m", ParameterType.DOUBLE, "m", -COORD_LIMIT_M, COORD_LIMIT_M, 0.0,
                            "Goal y in the lab frame."),
            ParameterSchema("speed_mps", ParameterType.DOUBLE, "m/s", 0.05, spec.max_linear_mps, 0.3,
                            "Cruising speed; the robot slows near obstacles and the goal."),
            ParameterSchema("max_error_m", ParameterType.DOUBLE, "m", 0.02, 1.0, 0.1,
                            "The goal counts as reached within this distance."),
            ParameterSchema("timeout_s", ParameterType.DOUBLE, "s", 1.0, 1800.0, 180.0,
                            "Abort with TIMEOUT after this much time."),
        ),
    )


class GoToGoal(SkillController):
    """Drives to (goal_x_m, goal_y_m) along an A* path over the detect-obstacle grid."""

    skill_class = "sensorimotor"  # chooses its wheel commands from what the sensors report

    def __init__(self, goal_x_m: float, goal_y_m: float, speed_mps: float, max_error_m: float,
                 timeout_s: float) -> None:
        super().__init__()
        self.goal = (goal_x_m, goal_y_m)
        self._speed_mps = speed_mps
        self._max_error_m = max_error_m
        self._timeout_s = timeout_s
        self._started_s: float | None = None
        self._start_distance_m = 0.0
        self._path: tuple[tuple[float, float], ...] = ()
        self._planned_s = -math.inf
        self._planned_version = -1
        self._trouble_since_s: float | None = None  # goal blocked or no path
        self._obstacle_xy: tuple[float, float] | None = None  # the seen obstacle the goal lies in, if so
        self._stuck_since_s: float | None = None
        self._closest_m = math.inf
        self._obstacle_announced = False
        self._state = "planning"

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Replans when needed, then steers toward a look-ahead point on the path."""
        now = tick.sim_time_s
        pose = tick.pose
        distance_m = math.hypot(self.goal[0] - pose.x_m, self.goal[1] - pose.y_m)
        if self._started_s is None:
            self._started_s = now
            self._start_distance_m = max(distance_m, 1e-6)
        bearing_error = heading_error(bearing_to(pose, *self.goal), pose)
        # Stop close in (a third of the tolerance leaves room for the pose estimate's own error), or as soon as
        # the distance starts growing again inside the tolerance (a pass).
        if distance_m <= max(STOP_FRACTION * self._max_error_m, 0.015) or (
            distance_m <= self._max_error_m and distance_m > self._closest_m + 0.002
        ):
            self.announce(EventKind.GOAL_REACHED, f"goal reached, {distance_m:.3f} m from it")
            return 0.0, 0.0, succeeded(f"reached the goal within {distance_m:.3f} m"), self._feedback(
                tick, "reached", distance_m, bearing_error)
        self._closest_m = min(self._closest_m, distance_m)
        if now - self._started_s > self._timeout_s:
            return 0.0, 0.0, aborted("TIMEOUT", f"gave up after {self._timeout_s:g} s, {distance_m:.2f} m from "
                                     "the goal"), self._feedback(tick, "timeout", distance_m, bearing_error)
        failure = self._update_plan(tick, distance_m)
        if failure is not None:
            return 0.0, 0.0, failure, self._feedback(tick, "unreachable", distance_m, bearing_error)
        linear, angular = self._steer(tick, distance_m)
        free = clearance(tick)
        if free.ahead_m < STOP_CLEARANCE_M + 0.02 and linear > 0:
            linear = 0.0
            if self._stuck_since_s is None:
                self._stuck_since_s = now
                self.announce(EventKind.OBSTACLE_DETECTED, f"obstacle {free.ahead_m:.2f} m ahead; stopping")
            elif now - self._stuck_since_s > STUCK_AFTER_S:
                return 0.0, 0.0, aborted("COLLISION_AHEAD", f"an obstacle {free.ahead_m:.2f} m ahead blocks the "
                                         "way and no way around was found"), self._feedback(
                    tick, "blocked", distance_m, bearing_error)
            self._planned_s = -math.inf  # look for a way around at once
        elif linear > 0:
            self._stuck_since_s = None
            linear = min(linear, max(0.05, 0.9 * (free.ahead_m - STOP_CLEARANCE_M)))
        return linear, angular, None, self._feedback(tick, self._state, distance_m, bearing_error)

    def _update_plan(self, tick: TickInput, distance_m: float) -> Outcome | None:
        grid = tick.obstacles
        if not isinstance(grid, ObstacleMap):
            self._path = (self.goal,)
            return None
        start = (tick.pose.x_m, tick.pose.y_m)
        radius_m = tick.spec.body_radius_m
        fresh = grid.version != self._planned_version
        due = tick.sim_time_s - self._planned_s >= REPLAN_PERIOD_S and fresh
        blocked = bool(self._path) and fresh and path_is_blocked(grid, self._path, radius_m, start)
        if self._path and not due and not blocked:
            return None
        if blocked and not self._obstacle_announced:
            self._obstacle_announced = True
            self.announce(EventKind.OBSTACLE_DETECTED, "an obstacle lies on the path; planning around it")
        if self._path or fresh or self._trouble_since_s is None:  # without a path, plan again on new evidence only
            plan = plan_path(grid, start, self.goal, radius_m)
            self._planned_s, self._planned_version = tick.sim_time_s, grid.version
            if plan.found:
                if blocked:
                    self.announce(EventKind.PATH_REPLANNED, f"new path of {len(plan.waypoints)} waypoints")
                self._path, self._trouble_since_s, self._state = plan.waypoints, None, "driving"
                return None
            self._path, self._obstacle_xy = (), plan.obstacle_xy
            if self._trouble_since_s is None:
                self._trouble_since_s = tick.sim_time_s
            self._state = "goal_blocked" if plan.goal_blocked else "no_path"
        assert self._trouble_since_s is not None
        if tick.sim_time_s - self._trouble_since_s < UNREACHABLE_AFTER_S:
            return None
        return aborted("UNREACHABLE", self._unreachable_message(grid, start, radius_m, distance_m))

    def _unreachable_message(self, grid: ObstacleMap, start: tuple[float, float], radius_m: float,
                             distance_m: float) -> str:
        """Why the goal cannot be reached, and the nearest point that can (numbers rounded for people)."""
        if self._state == "goal_blocked" and self._obstacle_xy is not None:
            why = f"the goal lies inside an obstacle (seen at {_point(self._obstacle_xy)})"
        else:
            why = "no path around the obstacles leads to the goal"
        nearest = nearest_reachable_point(grid, start, self.goal, radius_m)
        if nearest is not None and math.dist(nearest, start) > 0.05:
            offer = f"; the nearest point the robot can reach is {_point(nearest)}"
        else:
            offer = "; the robot can reach no point nearer to it than where it stands"
        return f"{why}{offer}, {math.dist(nearest, self.goal) if nearest else distance_m:.2f} m from the goal"

    def _steer(self, tick: TickInput, distance_m: float) -> tuple[float, float]:
        pose = tick.pose
        if not self._path:
            return 0.0, 0.0
        target = self._lookahead_point(pose.x_m, pose.y_m) if distance_m > LOOKAHEAD_M else self.goal
        error = heading_error(bearing_to(pose, *target), pose)
        angular = max(-1.2, min(1.2, 2.5 * error))
        if abs(error) > 0.6:
            return 0.0, angular  # turn on the spot before driving off sideways
        approach_mps = max(0.03, 0.7 * distance_m)  # arrive without overshooting the tolerance
        linear = min(self._speed_mps, approach_mps) * max(0.0, math.cos(error)) ** 2
        return linear, angular

    def _lookahead_point(self, x_m: float, y_m: float) -> tuple[float, float]:
        # Drop the waypoints already passed, then pick the first one a look-ahead away.
        while len(self._path) > 1 and math.hypot(self._path[0][0] - x_m, self._path[0][1] - y_m) < LOOKAHEAD_M:
            self._path = self._path[1:]
        return self._path[0]

    def _feedback(self, tick: TickInput, state: str, distance_m: float, bearing_error_rad: float) -> GoalFeedback:
        progress = 1.0 - distance_m / self._start_distance_m if self._start_distance_m else 0.0
        feedback = feedback_for(tick, state, progress, distance_m, bearing_error_rad,
                                goal_x_m=self.goal[0], goal_y_m=self.goal[1], waypoints=float(len(self._path)))
        return replace(feedback, planned_path=capped_path(self._path))  # the path ahead, planned from the belief


def _point(xy: tuple[float, float]) -> str:
    """A point as people write it: (1.05, 0.62), (1.2, -0.4)."""
    return "(" + ", ".join(f"{round(v, 2):g}" if round(v, 2) != 0 else "0" for v in xy) + ")"
