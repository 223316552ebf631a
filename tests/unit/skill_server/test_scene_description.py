"""The scene description is what the world builds and the camera renders: every body pybullet holds is in it,
with the same place, size and colour, and its version changes exactly when its content does."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import replace

import numpy as np
import pytest

from skill_server.sim.camera import CameraSpec, camera_eye_and_target
from skill_server.sim.geometry import Pose2D
from skill_server.sim.robot_model import TELEBOT
from skill_server.sim.scene_description import SceneDescription, content_version
from skill_server.sim.scenes import known_scenes
from skill_server.sim.world import (
    SURFACE_BACKGROUND,
    SURFACE_FLOOR,
    SURFACE_MARK,
    SURFACE_ROBOT,
    SURFACE_SOLID,
    World,
)

BOX, CYLINDER, SPHERE, MESH = 3, 4, 2, 5  # pybullet's GEOM_* numbers as getVisualShapeData reports them


@pytest.fixture(params=["lab", "course-B"])
def world(request: pytest.FixtureRequest) -> Iterator[World]:
    with World(request.param, realtime=False) as built:
        yield built


def rounded(*values: float) -> tuple[float, ...]:
    return tuple(round(v, 6) for v in values)


def scene_bodies_in_pybullet(world: World) -> list[tuple]:
    """(shape, centre xyz, size, rgba) of every body pybullet holds but the robot, read back from pybullet."""
    client = world._client
    found = []
    for body in range(client.getNumBodies()):
        if body == world._robot:
            continue
        (visual,) = client.getVisualShapeData(body)
        position, orientation = client.getBasePositionAndOrientation(body)
        yaw = client.getEulerFromQuaternion(orientation)[2]
        centre = np.add(position, visual[5])
        dims = visual[3]
        size = {BOX: (dims[0] / 2, dims[1] / 2, dims[2], yaw), CYLINDER: (dims[1], dims[0]), MESH: ()}[visual[2]]
        found.append((visual[2], rounded(*centre), rounded(*size), rounded(*visual[7])))
    return sorted(found)


def scene_bodies_described(scene: SceneDescription) -> list[tuple]:
    """The same tuples from the description (flat patches are meshes: their sizes are not read back)."""
    expected = [(MESH, rounded(p.center_x_m, p.center_y_m, p.top_z_m), (), rounded(*p.rgba))
                for p in (scene.floor, *scene.marks)]
    expected += [(BOX, rounded(b.center_x_m, b.center_y_m, b.height_m / 2), rounded(b.half_x_m, b.half_y_m,
                                                                                    b.height_m, b.yaw_rad),
                  rounded(*b.rgba)) for b in scene.boxes]
    expected += [(CYLINDER, rounded(c.center_x_m, c.center_y_m, c.height_m / 2), rounded(c.radius_m, c.height_m),
                  rounded(*c.rgba)) for c in scene.cylinders]
    return sorted(expected)


def test_every_scene_body_pybullet_holds_is_described_in_place_size_and_colour(world: World) -> None:
    assert scene_bodies_in_pybullet(world) == scene_bodies_described(world.describe_scene())


def test_the_robots_parts_are_the_visuals_pybullet_loaded(world: World) -> None:
    client, robot, spawn = world._client, world._robot, world.scene.spawn
    assert spawn.theta_rad == 0.0  # the robot's frame is the world's, shifted
    base_position, _ = client.getBasePositionAndOrientation(robot)
    base_frame = np.array([spawn.x_m, spawn.y_m, base_position[2] - client.getDynamicsInfo(robot, -1)[3][2]])
    loaded = []
    for visual in client.getVisualShapeData(robot):
        link = visual[1]
        link_frame = base_frame if link == -1 else np.array(client.getLinkState(robot, link)[4])
        position = link_frame + visual[5] - base_frame
        size = {BOX: lambda d: tuple(d), CYLINDER: lambda d: (d[1], d[1], d[0]),
                SPHERE: lambda d: (d[0], d[0], d[0])}[visual[2]](visual[3])
        loaded.append((visual[2], rounded(*position), rounded(*size), rounded(*visual[7])))
    shapes = {"box": BOX, "cylinder": CYLINDER, "sphere": SPHERE}
    described = [(shapes[p.shape], rounded(*p.position_m), rounded(*p.size_m), rounded(*p.rgba))
                 for p in world.describe_scene().robot_parts]
    assert sorted(loaded) == sorted(described)
    wheel = next(p for p in world.describe_scene().robot_parts if p.link == "left_wheel")
    assert wheel.orientation_xyzw == pytest.approx((math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)), abs=1e-5)


def test_the_camera_is_described_as_it_renders(world: World) -> None:
    camera = world.describe_scene().camera
    spec = world._camera.spec
    assert (camera.width_px, camera.height_px, camera.hfov_deg, camera.vfov_deg) == (
        spec.width_px, spec.height_px, spec.hfov_deg, spec.vfov_deg)
    assert (camera.near_m, camera.far_m) == (spec.near_m, spec.far_m)
    assert math.isclose(math.hypot(*camera.light_direction), 1.0)
    eye, target = camera_eye_and_target(TELEBOT, Pose2D(1.0, 2.0, math.pi / 2))
    assert eye == pytest.approx([1.0, 2.0 + camera.mount_forward_m, camera.mount_height_m])
    pitch = math.atan2(target[2] - eye[2], math.hypot(target[0] - eye[0], target[1] - eye[1]))
    assert pitch == pytest.approx(camera.mount_pitch_rad)


def test_the_described_lighting_predicts_the_rendered_colours() -> None:
    """A wall seen square on and the floor show their colours times the brightness the description's formula
    gives (pybullet truncates to bytes), so a view drawn from it shades as the server's camera does."""
    with World("lab", realtime=False) as world:
        world.set_pose(Pose2D(0.0, 0.0, 0.0))  # facing the east wall across the floor
        image = world.render_rgba()[:, :, :3].astype(float)
        scene = world.describe_scene()
    camera = scene.camera
    lx, ly, lz = camera.light_direction

    def brightness(nx: float, ny: float, nz: float) -> float:
        n_dot_l = nx * lx + ny * ly + nz * lz
        r_z = 2 * n_dot_l * nz - lz
        highlight = max(0.0, r_z) ** camera.specular_exponent
        lit = camera.light_diffuse * max(0.0, n_dot_l) + camera.light_specular * highlight
        return camera.light_ambient + min(lit, 1.0 - camera.light_ambient)

    east = next(b for b in scene.boxes if b.name == "wall_east")
    expected_wall = np.floor(np.floor(np.array(east.rgba[:3]) * 255) * brightness(-1.0, 0.0, 0.0))
    expected_floor = np.floor(np.floor(np.array(scene.floor.rgba[:3]) * 255) * brightness(0.0, 0.0, 1.0))
    assert image[20, 160] == pytest.approx(expected_wall, abs=1.0)
    assert image[200, 40] == pytest.approx(expected_floor, abs=1.0)
    assert image[0, 160] == pytest.approx(np.array(camera.background_rgba[:3]) * 255, abs=1.0)


def test_the_version_names_the_content() -> None:
    with World("lab", realtime=False) as one, World("lab", realtime=False, seed=7) as other:
        assert one.describe_scene().version == other.describe_scene().version  # noise seeds are not the world
        lab = one.describe_scene()
    assert lab.version == content_version(lab) and lab.version.startswith("sha256-")
    assert content_version(replace(lab, camera=replace(lab.camera, mount_height_m=0.31))) != lab.version
    with World("lab", realtime=False, camera=CameraSpec(hfov_deg=70.0)) as wide:
        assert wide.describe_scene().version != lab.version
    versions = set()
    for name in known_scenes():
        with World(name, realtime=False) as built:
            versions.add(built.describe_scene().version)
    assert len(versions) == len(known_scenes())


def test_marks_say_what_they_are() -> None:
    with World("course-B", realtime=False) as world:
        scene = world.describe_scene()
    kinds = [mark.kind for mark in scene.marks]
    assert kinds.count("track_line") == len(scene.track.lines) and kinds.count("track_point") == 2
    assert scene.floor.kind == "floor"
    assert [mark.top_z_m for mark in scene.marks] == sorted(mark.top_z_m for mark in scene.marks)


def test_the_camera_says_what_each_pixel_shows_from_the_same_rendering() -> None:
    """render_surfaces() draws the frame once and names each pixel's surface: the picture is render_rgba()'s."""
    with World("lab", realtime=False) as world:
        picture, surfaces = world.render_surfaces()  # at the dock, facing the red lane and the east wall
        assert (picture == world.render_rgba()).all()
    counts = np.bincount(surfaces.ravel(), minlength=5)
    assert counts[SURFACE_FLOOR] > counts[SURFACE_MARK] > 0 and counts[SURFACE_SOLID] > 0
    assert counts[SURFACE_ROBOT] == 0  # the robot never sees itself
    assert (surfaces[0] == SURFACE_BACKGROUND).all() and (surfaces[-1] != SURFACE_SOLID).all()
    lane = picture[200, 160, :3].astype(int)
    assert surfaces[200, 160] == SURFACE_MARK and lane[0] > lane[1] + 80  # the red lane is paint
