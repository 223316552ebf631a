"""The robot's camera: renders with pybullet's tiny renderer and encodes each frame to JPEG once."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import simplejpeg

from skill_server.sim.geometry import Pose2D
from skill_server.sim.robot_model import RobotSpec

DEFAULT_CAMERA_FPS = 15.0
MAX_CAMERA_FPS = 30.0
# What pybullet's TinyRenderer does that no argument sets: it clears to white, an untextured surface's highlight is
# max(0, r_z) ** 2 (r: the light reflected about the normal), and it samples each pixel at a corner instead of its
# centre: half a pixel left of it and half a pixel below it (x right, y down). A view drawn elsewhere from the scene
# description needs them to match pixel for pixel, so they are named here beside the lighting the camera passes.
RENDERER_BACKGROUND_RGBA = (1.0, 1.0, 1.0, 1.0)
RENDERER_SPECULAR_EXPONENT = 2.0
RENDERER_SAMPLE_OFFSET_PX = (-0.5, 0.5)


@dataclass(frozen=True)
class CameraSpec:
    """Image size, field of view and encoding of the camera."""

    width_px: int = 320
    height_px: int = 240
    hfov_deg: float = 60.0
    near_m: float = 0.05
    far_m: float = 20.0
    jpeg_quality: int = 80
    # The lighting the renderer is given: brightness = ambient + min(diffuse * max(0, n.l) + specular * highlight,
    # 1 - ambient), times the surface's colour.
    light_direction: tuple[float, float, float] = (0.4, -0.3, 1.0)  # toward the light, world frame, any length
    light_ambient: float = 0.6
    light_diffuse: float = 0.35
    light_specular: float = 0.05

    @property
    def vfov_deg(self) -> float:
        """Vertical field of view, which is what pybullet's projection takes."""
        half_h = math.tan(math.radians(self.hfov_deg) / 2.0)
        return math.degrees(2.0 * math.atan(half_h * self.height_px / self.width_px))


def camera_eye_and_target(robot: RobotSpec, pose: Pose2D) -> tuple[list[float], list[float]]:
    """Where the camera is and a point 1 m along its optical axis (world frame) for a robot at pose; up is +z."""
    cos_t, sin_t = math.cos(pose.theta_rad), math.sin(pose.theta_rad)
    eye = [pose.x_m + robot.camera_forward_m * cos_t, pose.y_m + robot.camera_forward_m * sin_t, robot.camera_height_m]
    cos_p, sin_p = math.cos(robot.camera_pitch_rad), math.sin(robot.camera_pitch_rad)
    return eye, [eye[0] + cos_t * cos_p, eye[1] + sin_t * cos_p, eye[2] + sin_p]


class Camera:
    """Renders from the camera mount of a robot at a given pose; call only from the world's thread."""

    def __init__(self, spec: CameraSpec, robot: RobotSpec) -> None:
        self.spec = spec
        self._robot = robot
        self._projection: list[float] | None = None

    def render_rgba(self, client: Any, pose: Pose2D) -> np.ndarray:
        """An (height, width, 4) uint8 image of what the camera sees."""
        return self._render(client, pose, with_body_ids=False)[0]

    def render_rgba_and_body_ids(self, client: Any, pose: Pose2D) -> tuple[np.ndarray, np.ndarray]:
        """The image and, per pixel, the id of the pybullet body it shows (-1: none), from one rendering."""
        rgba, body_ids = self._render(client, pose, with_body_ids=True)
        assert body_ids is not None
        return rgba, body_ids

    def _render(self, client: Any, pose: Pose2D, with_body_ids: bool) -> tuple[np.ndarray, np.ndarray | None]:
        spec, robot = self.spec, self._robot
        if self._projection is None:
            self._projection = client.computeProjectionMatrixFOV(
                fov=spec.vfov_deg,
                aspect=spec.width_px / spec.height_px,
                nearVal=spec.near_m,
                farVal=spec.far_m,
            )
        eye, target = camera_eye_and_target(robot, pose)
        view = client.computeViewMatrix(
            cameraEyePosition=eye, cameraTargetPosition=target, cameraUpVector=[0.0, 0.0, 1.0]
        )
        _, _, rgba, _, segmentation = client.getCameraImage(
            spec.width_px,
            spec.height_px,
            viewMatrix=view,
            projectionMatrix=self._projection,
            renderer=client.ER_TINY_RENDERER,
            shadow=0,
            lightDirection=list(spec.light_direction),
            lightAmbientCoeff=spec.light_ambient,
            lightDiffuseCoeff=spec.light_diffuse,
            lightSpecularCoeff=spec.light_specular,
            flags=0 if with_body_ids else client.ER_NO_SEGMENTATION_MASK,
        )
        image = np.asarray(rgba, dtype=np.uint8).reshape(spec.height_px, spec.width_px, 4)
        if not with_body_ids:
            return image, None
        return image, np.asarray(segmentation, dtype=np.int64).reshape(spec.height_px, spec.width_px)

    def render_jpeg(self, client: Any, pose: Pose2D) -> bytes:
        """One rendered frame, JPEG-encoded."""
        return encode_jpeg(self.render_rgba(client, pose), self.spec.jpeg_quality)


def encode_jpeg(rgba: np.ndarray, quality: int) -> bytes:
    """JPEG bytes of an RGBA image (the alpha channel is dropped by the encoder)."""
    return simplejpeg.encode_jpeg(np.ascontiguousarray(rgba), quality=quality, colorspace="RGBA")
