"""Constants and test scenes shared by the robot core's unit tests (registered on import)."""

from __future__ import annotations

from skill_server.sim.geometry import Pose2D
from skill_server.sim.scenes import BoxObstacle, CylinderObstacle, SceneSpec, register_scene

WALL_FACE_X_M = 2.0  # the test wall's face toward the robot
POLE_RADIUS_M = 0.03

TOKEN = "controller-token"


def _wall_scene() -> SceneSpec:
    return SceneSpec(
        name="test_wall",
        floor_half_x_m=5.0,
        floor_half_y_m=5.0,
        boxes=(BoxObstacle("wall", WALL_FACE_X_M + 0.05, 0.0, 0.05, 3.0, 1.0, (0.8, 0.2, 0.2, 1.0)),),
        spawn=Pose2D(0.0, 0.0, 0.0),
    )


def _pole_scene() -> SceneSpec:
    # A thin pole 1.5 m from the front sonar, 8 degrees off its axis: inside the cone, beside the axis ray.
    return SceneSpec(
        name="test_pole",
        floor_half_x_m=5.0,
        floor_half_y_m=5.0,
        cylinders=(CylinderObstacle("pole", 1.685, 0.209, POLE_RADIUS_M, 1.0, (0.2, 0.2, 0.8, 1.0)),),
    )


register_scene("test_wall", _wall_scene)
register_scene("test_pole", _pole_scene)
