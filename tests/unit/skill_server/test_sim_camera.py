"""The camera renders the scene upright, encodes once, and only while someone watches."""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np
import pytest
import simplejpeg

from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import World


@pytest.fixture
def lab_world() -> Iterator[World]:
    with World("lab", realtime=False) as world:
        yield world


def test_a_frame_is_a_320x240_jpeg_with_its_metadata(lab_world: World) -> None:
    frame = lab_world.render_frame()
    assert frame.jpeg[:2] == b"\xff\xd8"
    assert simplejpeg.decode_jpeg(frame.jpeg).shape == (240, 320, 3)
    assert (frame.width_px, frame.height_px, frame.frame_sequence) == (320, 240, 1)
    assert frame.pose_at_capture == lab_world.snapshot.odometry.pose


def test_the_image_is_upright_and_not_mirrored(lab_world: World) -> None:
    # Facing +x from the origin: the red east wall fills the top, the grey floor the bottom,
    # and the red lane painted ahead runs up the middle of the lower half.
    image = lab_world.render_rgba()[:, :, :3].astype(int)
    top, bottom = image[10, 160], image[230, 40]
    assert top[0] > top[1] + 50 and top[0] > top[2] + 50
    assert abs(bottom[0] - bottom[1]) < 20 and abs(bottom[1] - bottom[2]) < 20
    lane = image[200, 160]
    assert lane[0] > lane[1] + 80
    # The crate at (2.5, 1.4) is to the robot's left, so it must appear in the left half.
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    brown = (green > blue + 20) & (red > green + 20)  # the red wall has green close to blue
    columns = np.nonzero(brown[:55].any(axis=0))[0]
    assert columns.size and columns.mean() < 100
    # Turned left by 43 degrees, the crate moves to the right half (rows above the horizon only).
    lab_world.set_pose(Pose2D(0.0, 0.0, 0.75))
    turned = lab_world.render_rgba()[:, :, :3].astype(int)
    brown = (turned[..., 1] > turned[..., 2] + 20) & (turned[..., 0] > turned[..., 1] + 20)
    assert np.nonzero(brown[:55].any(axis=0))[0].mean() > 160


def test_the_camera_renders_only_while_subscribed_at_the_highest_fps() -> None:
    with World("lab", realtime=False) as world:
        world.start()
        time.sleep(0.3)
        assert world.latest_frame is None
        with world.subscribe_camera(5.0), world.subscribe_camera(20.0):
            first = world.wait_for_frame(0, timeout_s=5.0)
            assert first is not None
            later = world.wait_for_frame(first.frame_sequence + 9, timeout_s=10.0)
            assert later is not None
            frames = later.frame_sequence - first.frame_sequence
            assert later.sim_time_s - first.sim_time_s == pytest.approx(frames / 20.0, rel=0.1)
        assert world.camera_subscriber_count == 0
        time.sleep(0.2)
        last = world.latest_frame
        time.sleep(0.3)
        assert world.latest_frame is last
