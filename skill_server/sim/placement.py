"""Where a robot may be placed by hand: on its scene's floor, its body clear of every wall and obstacle."""

from __future__ import annotations

import math

from skill_server.errors import InvalidParameter
from skill_server.sim.geometry import Pose2D
from skill_server.sim.scenes import SceneSpec


def check_placement(scene: SceneSpec, pose: Pose2D, body_radius_m: float) -> None:
    """Raises InvalidParameter naming the field (pose.x_m, pose.y_m, pose.theta_rad or pose) unless a body of
    body_radius_m fits at pose."""
    for name in ("x_m", "y_m", "theta_rad"):
        if not math.isfinite(getattr(pose, name)):
            raise InvalidParameter(f"pose.{name}", f"pose.{name} must be a finite number")
    for name, value, half in (("x_m", pose.x_m, scene.floor_half_x_m), ("y_m", pose.y_m, scene.floor_half_y_m)):
        if abs(value) > half:
            raise InvalidParameter(f"pose.{name}", f"pose.{name} {value:.3f} is off the floor (|{name}| <= {half})")
    for box in scene.boxes:
        dx, dy = pose.x_m - box.center_x_m, pose.y_m - box.center_y_m
        cos, sin = math.cos(box.yaw_rad), math.sin(box.yaw_rad)
        local_x, local_y = cos * dx + sin * dy, -sin * dx + cos * dy
        gap_x, gap_y = max(abs(local_x) - box.half_x_m, 0.0), max(abs(local_y) - box.half_y_m, 0.0)
        if math.hypot(gap_x, gap_y) < body_radius_m:
            raise InvalidParameter("pose", f"the robot's body would overlap {box.name}")
    for cylinder in scene.cylinders:
        gap = math.hypot(pose.x_m - cylinder.center_x_m, pose.y_m - cylinder.center_y_m) - cylinder.radius_m
        if gap < body_radius_m:
            raise InvalidParameter("pose", f"the robot's body would overlap {cylinder.name}")
