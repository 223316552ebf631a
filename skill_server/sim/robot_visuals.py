"""The robot's visible parts, read from the URDF pybullet loads, placed in the robot's base frame."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass

import numpy as np

from skill_server.sim.robot_model import URDF_PATH

SHAPES = ("box", "cylinder", "sphere")


@dataclass(frozen=True)
class VisualPart:
    """One visual of one link: a box, a cylinder (along its local z, as in URDF) or a sphere."""

    link: str
    shape: str  # one of SHAPES
    size_m: tuple[float, float, float]  # box: full x, y, z; cylinder: radius, radius, length; sphere: radius x 3
    position_m: tuple[float, float, float]  # in the base frame: origin on the floor under the axle's centre, x ahead
    orientation_xyzw: tuple[float, float, float, float]  # quaternion, base frame
    rgba: tuple[float, float, float, float]


def robot_visual_parts(urdf: str | None = None) -> tuple[VisualPart, ...]:
    """Every visual of the URDF (the robot's own file by default), each link placed through its joints."""
    root = ElementTree.fromstring(urdf if urdf is not None else URDF_PATH.read_text())
    parent_of: dict[str, tuple[str, np.ndarray]] = {}
    for joint in root.findall("joint"):
        parent = _required(joint.find("parent"), "parent").get("link", "")
        child = _required(joint.find("child"), "child").get("link", "")
        parent_of[child] = (parent, _origin(joint.find("origin")))
    parts: list[VisualPart] = []
    for link in root.findall("link"):
        name = link.get("name", "")
        link_in_base = _link_in_base(name, parent_of)
        for visual in link.findall("visual"):
            placed = link_in_base @ _origin(visual.find("origin"))
            shape, size = _geometry(_required(visual.find("geometry"), "geometry"))
            colour = visual.find("material/color")
            rgba = tuple(float(v) for v in colour.get("rgba", "1 1 1 1").split()) if colour is not None else (1.0,) * 4
            parts.append(VisualPart(
                link=name, shape=shape, size_m=size,
                position_m=(float(placed[0, 3]), float(placed[1, 3]), float(placed[2, 3])),
                orientation_xyzw=_quaternion(placed[:3, :3]),
                rgba=(rgba[0], rgba[1], rgba[2], rgba[3]),
            ))
    return tuple(parts)


def _required(element: ElementTree.Element | None, what: str) -> ElementTree.Element:
    if element is None:
        raise ValueError(f"the URDF lacks a <{what}> element where one is required")
    return element


def _link_in_base(link: str, parent_of: dict[str, tuple[str, np.ndarray]]) -> np.ndarray:
    """The link's frame in the root link's frame (joints at rest)."""
    transform = np.eye(4)
    while link in parent_of:
        link, joint_origin = parent_of[link]
        transform = joint_origin @ transform
    return transform


def _origin(origin: ElementTree.Element | None) -> np.ndarray:
    """The 4x4 transform of a URDF <origin xyz rpy> (identity when absent)."""
    transform = np.eye(4)
    if origin is None:
        return transform
    x, y, z = (float(v) for v in origin.get("xyz", "0 0 0").split())
    roll, pitch, yaw = (float(v) for v in origin.get("rpy", "0 0 0").split())
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw),
                              math.sin(yaw))
    # URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll).
    transform[:3, :3] = [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
    transform[:3, 3] = (x, y, z)
    return transform


def _geometry(geometry: ElementTree.Element) -> tuple[str, tuple[float, float, float]]:
    box, cylinder, sphere = geometry.find("box"), geometry.find("cylinder"), geometry.find("sphere")
    if box is not None:
        sx, sy, sz = (float(v) for v in box.get("size", "0 0 0").split())
        return "box", (sx, sy, sz)
    if cylinder is not None:
        radius = float(cylinder.get("radius", "0"))
        return "cylinder", (radius, radius, float(cylinder.get("length", "0")))
    if sphere is not None:
        radius = float(sphere.get("radius", "0"))
        return "sphere", (radius, radius, radius)
    raise ValueError("a visual of the URDF has a geometry other than box, cylinder or sphere")


def _quaternion(rotation: np.ndarray) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation matrix, w >= 0."""
    w = math.sqrt(max(0.0, 1.0 + rotation[0, 0] + rotation[1, 1] + rotation[2, 2])) / 2.0
    x = math.copysign(math.sqrt(max(0.0, 1.0 + rotation[0, 0] - rotation[1, 1] - rotation[2, 2])) / 2.0,
                      rotation[2, 1] - rotation[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - rotation[0, 0] + rotation[1, 1] - rotation[2, 2])) / 2.0,
                      rotation[0, 2] - rotation[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - rotation[0, 0] - rotation[1, 1] + rotation[2, 2])) / 2.0,
                      rotation[1, 0] - rotation[0, 1])
    return (x, y, z, w)
