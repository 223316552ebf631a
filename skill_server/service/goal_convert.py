"""Proto <-> domain translation of goals, parameters, maps and localization estimates."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from protos.telelab.v1 import robot_pb2
from skill_server.errors import InvalidParameter
from skill_server.goals import EventKind, GoalEvent, GoalFeedback, GoalSnapshot, GoalStatus
from skill_server.service.convert import pose_to_proto
from skill_server.sim.snapshots import RobotSnapshot

_STATUS = {status: getattr(robot_pb2, f"GOAL_STATUS_{status.name}") for status in GoalStatus}
_EVENT = {kind: getattr(robot_pb2, f"GOAL_EVENT_KIND_{kind.name}") for kind in EventKind}


def parameters_from_proto(values: Mapping[str, robot_pb2.ParameterValue]) -> dict[str, object]:
    """Plain Python values (float, int, bool, str) from the request's map; an empty value is refused."""
    plain: dict[str, object] = {}
    for name, value in values.items():
        kind = value.WhichOneof("kind")
        if kind is None:
            raise InvalidParameter(name, f"{name} has no value")
        plain[name] = getattr(value, kind)
    return plain


def parameter_to_proto(value: float | int | bool | str) -> robot_pb2.ParameterValue:
    """One validated value as a ParameterValue."""
    if isinstance(value, bool):
        return robot_pb2.ParameterValue(bool_value=value)
    if isinstance(value, int):
        return robot_pb2.ParameterValue(int_value=value)
    if isinstance(value, str):
        return robot_pb2.ParameterValue(string_value=value)
    return robot_pb2.ParameterValue(double_value=value)


def feedback_to_proto(feedback: GoalFeedback) -> robot_pb2.GoalFeedback:
    """A goal's feedback."""
    return robot_pb2.GoalFeedback(
        sim_time_s=feedback.sim_time_s,
        state=feedback.state,
        progress=feedback.progress,
        distance_error_m=feedback.distance_error_m,
        heading_error_rad=feedback.heading_error_rad,
        pose=pose_to_proto(feedback.pose),
        pose_source=feedback.pose_source,
        values={name: value for name, value in feedback.values if math.isfinite(value)},
    )


def event_to_proto(index: int, event: GoalEvent) -> robot_pb2.GoalEvent:
    """One event with its position in the log."""
    return robot_pb2.GoalEvent(index=index, sim_time_s=event.sim_time_s, kind=_EVENT[event.kind],
                               message=event.message)


def goal_to_proto(goal: GoalSnapshot) -> robot_pb2.GoalState:
    """A goal's state."""
    return robot_pb2.GoalState(
        goal_id=goal.goal_id,
        skill=goal.skill,
        motor=goal.motor,
        status=_STATUS[goal.status],
        parameters={name: parameter_to_proto(value) for name, value in goal.parameters},
        accepted_sim_s=goal.accepted_sim_s,
        ended_sim_s=goal.ended_sim_s or 0.0,
        error_code=goal.error_code,
        message=goal.message,
        feedback=feedback_to_proto(goal.feedback),
        goal_reached=goal.goal_reached,
    )


def grid_to_proto(grid: Any) -> robot_pb2.OccupancyGrid:
    """The environment model's published grid."""
    return robot_pb2.OccupancyGrid(
        resolution_m=grid.resolution_m,
        origin_x_m=grid.origin_x_m,
        origin_y_m=grid.origin_y_m,
        width_cells=grid.width_cells,
        height_cells=grid.height_cells,
        cells=grid.cells,
        scans_integrated=grid.scans_integrated,
        sim_time_s=grid.sim_time_s,
    )


def localization_to_proto(snapshot: RobotSnapshot, estimate: Any, max_particles: int) -> robot_pb2.LocalizationUpdate:
    """The estimate beside odometry and ground truth, with their errors."""
    truth, odometry = snapshot.ground_truth, snapshot.odometry.pose
    update = robot_pb2.LocalizationUpdate(
        sim_time_s=snapshot.sim_time_s,
        odometry=pose_to_proto(odometry),
        ground_truth=pose_to_proto(truth),
        odometry_position_error_m=truth.distance_to(odometry),
        odometry_heading_error_rad=abs(math.remainder(odometry.theta_rad - truth.theta_rad, 2 * math.pi)),
    )
    if estimate is None:
        return update
    pose = estimate.pose
    update.active = True
    update.converged = estimate.converged
    update.estimate.CopyFrom(pose_to_proto(pose))
    update.std_x_m, update.std_y_m, update.std_theta_rad = estimate.std_x_m, estimate.std_y_m, estimate.std_theta_rad
    update.position_error_m = truth.distance_to(pose)
    update.heading_error_rad = abs(math.remainder(pose.theta_rad - truth.theta_rad, 2 * math.pi))
    update.update_duration_ms = estimate.update_duration_ms
    for x_m, y_m, theta_rad, weight in estimate.particles[:max_particles]:
        update.particles.add(x_m=x_m, y_m=y_m, theta_rad=theta_rad, weight=weight)
    return update
