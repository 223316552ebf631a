"""The robot's static world as data: what a view drawn elsewhere (the browser's 3D lab and robot's-eye views)
needs to match the world and its camera, taken from the very objects the world builds from.

The floor and the marks come from `scenes.floor_patches`, which `build_scene` also uses; walls and obstacles are
the scene's own boxes and cylinders; the robot's parts are read from the URDF file pybullet loads; the camera's
mount, intrinsics and lighting are the `RobotSpec` and `CameraSpec` the camera renders with. The version is a hash
of all of it, so a client that holds a version holds exactly this content.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, replace

from skill_server.sim.camera import (
    RENDERER_BACKGROUND_RGBA,
    RENDERER_SAMPLE_OFFSET_PX,
    RENDERER_SPECULAR_EXPONENT,
    CameraSpec,
)
from skill_server.sim.geometry import Pose2D
from skill_server.sim.laser import LaserSpec
from skill_server.sim.robot_model import RobotSpec
from skill_server.sim.robot_visuals import VisualPart, robot_visual_parts
from skill_server.sim.scenes import BoxObstacle, CylinderObstacle, FloorPatch, RoomCamera, SceneSpec, floor_patches
from skill_server.sim.sonar import SonarGeometry, SonarRingSpec
from skill_server.sim.track_monitor import TrackSpec

Rgba = tuple[float, float, float, float]


@dataclass(frozen=True)
class CameraModel:
    """The robot's camera as its renderer sees it: mount, intrinsics, clipping planes and lighting."""

    width_px: int
    height_px: int
    hfov_deg: float
    vfov_deg: float
    near_m: float
    far_m: float
    mount_forward_m: float  # [m] ahead of the robot's centre
    mount_height_m: float  # [m] above the floor
    mount_pitch_rad: float  # negative looks down; no roll, up is +z
    light_direction: tuple[float, float, float]  # unit vector toward the light, world frame
    light_ambient: float
    light_diffuse: float
    light_specular: float
    specular_exponent: float
    background_rgba: Rgba
    sample_offset_px: tuple[float, float]  # where each pixel is sampled from its centre, x right, y down [px]


@dataclass(frozen=True)
class SonarMounts:
    """The sonar ring: where on the robot the sonars sit and what each covers."""

    mount_radius_m: float  # [m] from the robot's centre; ranges are measured from there
    height_m: float
    sonars: tuple[SonarGeometry, ...]


@dataclass(frozen=True)
class SceneDescription:
    """Everything static a view of the robot's world needs; version is a hash of the rest."""

    version: str
    scene_name: str
    floor: FloorPatch
    marks: tuple[FloorPatch, ...]  # painted in this order: a later mark covers an earlier one
    boxes: tuple[BoxObstacle, ...]  # walls are boxes too
    cylinders: tuple[CylinderObstacle, ...]
    track: TrackSpec | None
    spawn: Pose2D
    body_radius_m: float
    robot_parts: tuple[VisualPart, ...]
    camera: CameraModel
    laser: LaserSpec
    sonar: SonarMounts
    room_cameras: tuple[RoomCamera, ...] = ()


def camera_model(camera: CameraSpec, robot: RobotSpec) -> CameraModel:
    """The camera of a robot as CameraSpec and RobotSpec define it (the light direction made a unit vector)."""
    lx, ly, lz = camera.light_direction
    norm = math.sqrt(lx * lx + ly * ly + lz * lz)
    return CameraModel(
        width_px=camera.width_px, height_px=camera.height_px, hfov_deg=camera.hfov_deg, vfov_deg=camera.vfov_deg,
        near_m=camera.near_m, far_m=camera.far_m, mount_forward_m=robot.camera_forward_m,
        mount_height_m=robot.camera_height_m, mount_pitch_rad=robot.camera_pitch_rad,
        light_direction=(lx / norm, ly / norm, lz / norm), light_ambient=camera.light_ambient,
        light_diffuse=camera.light_diffuse, light_specular=camera.light_specular,
        specular_exponent=RENDERER_SPECULAR_EXPONENT, background_rgba=RENDERER_BACKGROUND_RGBA,
        sample_offset_px=RENDERER_SAMPLE_OFFSET_PX,
    )


def describe_scene(scene: SceneSpec, robot: RobotSpec, camera: CameraSpec, laser: LaserSpec,
                   sonar: SonarRingSpec) -> SceneDescription:
    """The description of a robot in a scene, with its version."""
    floor, *marks = floor_patches(scene)
    description = SceneDescription(
        version="",
        scene_name=scene.name,
        floor=floor,
        marks=tuple(marks),
        boxes=scene.boxes,
        cylinders=scene.cylinders,
        track=scene.track,
        spawn=scene.spawn,
        body_radius_m=robot.body_radius_m,
        robot_parts=robot_visual_parts(),
        camera=camera_model(camera, robot),
        laser=laser,
        sonar=SonarMounts(sonar.mount_radius_m, sonar.height_m, sonar.geometries()),
        room_cameras=scene.room_cameras,
    )
    return replace(description, version=content_version(description))


def content_version(description: SceneDescription) -> str:
    """A hash of everything but the version itself (dataclass reprs print every field, floats exactly)."""
    content = repr(replace(description, version=""))
    return "sha256-" + hashlib.sha256(content.encode()).hexdigest()[:32]
