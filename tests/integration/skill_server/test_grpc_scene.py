"""GetScene over real gRPC: the static world once, versioned, and only the version to a caller that holds it."""

from __future__ import annotations

import math

import grpc

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.server import create_server

DEADLINE_S = 10.0


def test_the_scene_describes_the_lab_its_robot_camera_and_sensors(robot: robot_pb2_grpc.RobotStub) -> None:
    scene = robot.GetScene(robot_pb2.GetSceneRequest(), timeout=DEADLINE_S)
    assert scene.scene_name == "lab" and scene.version.startswith("sha256-") and not scene.unchanged
    assert scene.floor.kind == robot_pb2.FLOOR_PATCH_KIND_FLOOR and scene.floor.top_z_m == 0.0
    assert (scene.floor.half_x_m, scene.floor.half_y_m) == (4.5, 3.5)  # the room and a margin past the walls
    walls = {b.name: b for b in scene.blocks if b.name.startswith("wall_")}
    assert len(walls) == 4 and walls["wall_east"].colour.r > 0.7 and walls["wall_east"].height_m == 1.0
    assert [c.name for c in scene.cylinders] == ["pillar"]
    kinds = {mark.kind for mark in scene.marks}
    assert {robot_pb2.FLOOR_PATCH_KIND_GRID, robot_pb2.FLOOR_PATCH_KIND_PAINT} <= kinds
    lane = next(m for m in scene.marks if m.colour.r > 0.8 and m.colour.g < 0.2)  # the red lane ahead of the dock
    assert (lane.center_x_m, lane.half_x_m) == (2.0, 1.5)
    assert not scene.HasField("track")
    assert {p.link for p in scene.robot_parts} >= {"base_link", "left_wheel", "right_wheel", "camera_mount"}
    camera = scene.camera
    assert (camera.width_px, camera.height_px, camera.hfov_deg) == (320, 240, 60.0)
    assert math.isclose(camera.vfov_deg, math.degrees(2 * math.atan(math.tan(math.radians(30)) * 240 / 320)))
    assert (camera.mount_forward_m, camera.mount_height_m) == (0.17, 0.30)
    assert math.isclose(camera.mount_pitch_rad, math.radians(-12.0))
    assert (camera.light_ambient, camera.light_diffuse, camera.light_specular) == (0.6, 0.35, 0.05)
    assert (scene.laser.beam_count, scene.laser.height_m) == (181, 0.20)
    assert len(scene.sonar.sonars) == 16 and scene.sonar.mount_radius_m == scene.body_radius_m == 0.20


def test_a_caller_holding_the_version_gets_only_the_version(robot: robot_pb2_grpc.RobotStub) -> None:
    full = robot.GetScene(robot_pb2.GetSceneRequest(), timeout=DEADLINE_S)
    again = robot.GetScene(robot_pb2.GetSceneRequest(known_version=full.version), timeout=DEADLINE_S)
    assert again.unchanged and again.version == full.version
    assert again.ByteSize() < 100 < full.ByteSize()
    assert not again.blocks and not again.HasField("camera")
    stale = robot.GetScene(robot_pb2.GetSceneRequest(known_version="sha256-0000"), timeout=DEADLINE_S)
    assert not stale.unchanged and stale == full


def test_a_track_scene_carries_its_track_and_a_version_of_its_own(robot: robot_pb2_grpc.RobotStub) -> None:
    lab_version = robot.GetScene(robot_pb2.GetSceneRequest(), timeout=DEADLINE_S).version
    running = create_server(port=0, realtime=False, scene="course-B")
    try:
        with grpc.insecure_channel(running.address) as channel:
            scene = robot_pb2_grpc.RobotStub(channel).GetScene(robot_pb2.GetSceneRequest(known_version=lab_version),
                                                                 timeout=DEADLINE_S)
    finally:
        running.stop(grace_s=0.5)
    assert not scene.unchanged and scene.version != lab_version and scene.scene_name == "course-B"
    assert len(scene.track.lines) == 8 and (scene.track.a_x_m, scene.track.b_x_m) == (-3.0, 3.0)
    lines = [m for m in scene.marks if m.kind == robot_pb2.FLOOR_PATCH_KIND_TRACK_LINE]
    assert len(lines) == 8 and all(m.colour.r > 0.9 for m in lines)
    assert (scene.spawn.x_m, scene.spawn.y_m) == (-3.0, -1.5)
