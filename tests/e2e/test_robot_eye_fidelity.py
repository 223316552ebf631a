"""The robot's-eye view drawn by three.js in Debian's Chromium against the skill server's own camera frames, at the
same poses (near walls, facing obstacles, facing the track's lines), in the lab and on track B.

Masks: what each pixel shows, wall or obstacle, floor, or a line or other mark painted on the floor. The server's
come from the frame's own rendering (pybullet's per-pixel body ids, `World.render_surfaces`); the browser's from
the same meshes and camera as its picture, drawn with one flat code per surface (`RobotEyeRenderer.renderSurfaces`).
Masks from colours alone are ill-defined here: the grey pillar, lit from the side, takes the floor's grey. The
pictures themselves are compared too: the browser's colours against the JPEG frame a viewer receives.
"""

from __future__ import annotations

import base64
import functools
import json
import math
import struct
import threading
import zlib
from collections.abc import Iterator
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import numpy as np
import pytest
import simplejpeg

from middleware.browser_modules import import_map_text
from middleware.robots.scene import scene_dict
from skill_server.service import convert
from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import SURFACE_FLOOR, SURFACE_MARK, SURFACE_SOLID, World
from tests.conftest import ARTIFACTS_DIR

pytestmark = pytest.mark.e2e
STATIC_DIR = Path(__file__).resolve().parents[2] / "client_ui" / "static"
THREE_MODULE = STATIC_DIR / "vendor/node_modules/three/build/three.module.js"
MASKS = {"walls": SURFACE_SOLID, "floor": SURFACE_FLOOR, "lines": SURFACE_MARK}
MIN_IOU = 0.9
MAX_MEAN_COLOUR_DIFFERENCE = 4.0  # [levels of 255] per channel, where both say the same surface
POSES = {
    "lab": [
        (0.0, 0.0, 0.0),  # the dock, facing the red lane and the east wall
        (3.3, 0.5, 0.2),  # half a metre from the east wall
        (-1.0, 0.5, 2.5),  # facing the cabinet from close by
        (1.0, -1.0, -0.6),  # the pillar, lit from the side
        (-3.2, -2.3, 0.9),  # in the south-west corner, over the grid and the purple tile
        (2.0, 1.8, -2.8),  # beside the crate, looking back across the room
    ],
    "course-B": [
        (-2.8, -1.5, 0.0),  # just off A, facing the corridor's lines
        (-0.5, -1.2, 1.2),  # turning into the second leg, lines on both sides
        (0.0, 0.0, 1.57),  # in the second leg, facing north
        (1.0, 1.5, 0.1),  # in the last leg, facing B
        (2.9, 1.2, 2.5),  # at B, close to the lines and the north wall
    ],
}
RENDER = """async ([scene, pose, what]) => {
  const { RobotEyeRenderer } = await import('/lib/robot-eye.js');
  window.views ??= new Map();
  const key = scene.version + JSON.stringify(scene.camera);
  if (!window.views.has(key)) {
    const canvas = document.createElement('canvas');
    document.body.append(canvas);
    window.views.set(key, new RobotEyeRenderer(canvas, scene));
  }
  const view = window.views.get(key);
  let pixels;
  if (what === 'surfaces') pixels = view.renderSurfaces(pose);
  else { view.render(pose); pixels = view.readPixels(); }
  let text = '';
  for (let i = 0; i < pixels.length; i += 0x8000) text += String.fromCharCode(...pixels.subarray(i, i + 0x8000));
  return btoa(text);
}"""


class _QuietHandler(SimpleHTTPRequestHandler):
    extensions_map = {**SimpleHTTPRequestHandler.extensions_map, ".js": "text/javascript"}

    def log_message(self, *_args) -> None:
        pass


@pytest.fixture(scope="module")
def eye_page(chromium) -> Iterator:
    """A tab on client_ui/static (served as the middleware serves it) with the app's import map for three.js."""
    if not THREE_MODULE.exists():
        pytest.fail("three.js is not installed: `make test` (or `make three`) runs npm ci in client_ui/static/vendor.")
    server = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_QuietHandler, directory=str(STATIC_DIR)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    context = chromium.new_context()
    tab = context.new_page()
    errors: list[str] = []
    tab.on("pageerror", lambda error: errors.append(str(error)))
    tab.goto(f"http://127.0.0.1:{server.server_port}/lib/")
    tab.evaluate("(text) => { const map = document.createElement('script'); map.type = 'importmap';"
                 " map.textContent = text; document.head.append(map); }", import_map_text("/"))
    yield tab
    context.close()
    server.shutdown()
    server.server_close()
    assert not errors, errors


@pytest.fixture(scope="module", params=list(POSES))
def world(request: pytest.FixtureRequest) -> Iterator[World]:
    with World(request.param, realtime=False) as built:
        yield built


def browser_view(page, scene: dict, pose: tuple[float, float, float], what: str) -> np.ndarray:
    """The browser's picture (H x W x 4) or its surface codes (H x W) of the robot at pose."""
    camera = scene["camera"]
    shape = (camera["height_px"], camera["width_px"]) + ((4,) if what == "image" else ())
    answer = page.evaluate(RENDER, [scene, {"x_m": pose[0], "y_m": pose[1], "theta_rad": pose[2]}, what])
    return np.frombuffer(base64.b64decode(answer), np.uint8).reshape(shape)


def server_view(world: World, pose: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """The server camera's surfaces at pose and the JPEG frame it streams from there, decoded."""
    world.set_pose(Pose2D(*pose))
    _, surfaces = world.render_surfaces()
    return surfaces, simplejpeg.decode_jpeg(world.render_frame().jpeg)


def mask_ious(server: np.ndarray, browser: np.ndarray) -> dict[str, float]:
    """Intersection over union of each mask (NaN where neither view shows that surface)."""
    ious = {}
    for name, code in MASKS.items():
        union = np.count_nonzero((server == code) | (browser == code))
        ious[name] = np.count_nonzero((server == code) & (browser == code)) / union if union else math.nan
    return ious


def write_png(path: Path, rgb: np.ndarray) -> None:
    """An 8-bit RGB PNG (the suite has no imaging library)."""
    height, width, _ = rgb.shape
    rows = b"".join(b"\x00" + np.ascontiguousarray(rgb[y, :, :3], np.uint8).tobytes() for y in range(height))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def test_the_robots_eye_view_matches_the_servers_frames(eye_page, world: World) -> None:
    scene = scene_dict(convert.scene_to_proto(world.describe_scene()))
    figures, pictures = [], []
    for pose in POSES[world.scene.name]:
        server_surfaces, frame = server_view(world, pose)
        surfaces = browser_view(eye_page, scene, pose, "surfaces")
        picture = browser_view(eye_page, scene, pose, "image")[:, :, :3]
        same = server_surfaces == surfaces
        colour_difference = float(np.abs(picture.astype(int) - frame.astype(int))[same].mean())
        figures.append({"pose": pose, **mask_ious(server_surfaces, surfaces), "same_surface": float(same.mean()),
                        "mean_colour_difference": round(colour_difference, 2)})
        pictures.append(np.concatenate([frame, picture], axis=1))
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    write_png(ARTIFACTS_DIR / f"robot-eye-{world.scene.name}.png", np.concatenate(pictures, axis=0))
    (ARTIFACTS_DIR / f"robot-eye-{world.scene.name}.json").write_text(json.dumps(figures, indent=1))
    for figure in figures:
        shown = {name: figure[name] for name in MASKS if not math.isnan(figure[name])}
        assert shown and min(shown.values()) >= MIN_IOU, f"masks disagree at {figure['pose']}: {figure}"
        assert figure["mean_colour_difference"] <= MAX_MEAN_COLOUR_DIFFERENCE, f"colours differ: {figure}"
    seen = {name for figure in figures for name in MASKS if figure[name] == figure[name]}
    assert seen == set(MASKS), "some surface was never in view: the poses test less than they claim"


def wrong(scene: dict, *, mount_height_m: float = 0.0, hfov_factor: float = 1.0) -> dict:
    """The scene with its camera mounted higher or lower, or seeing wider or narrower, than the server's."""
    changed = json.loads(json.dumps(scene))
    camera = changed["camera"]
    camera["mount_height_m"] += mount_height_m
    camera["hfov_deg"] *= hfov_factor
    half_width = math.tan(math.radians(camera["hfov_deg"]) / 2)
    camera["vfov_deg"] = math.degrees(2 * math.atan(half_width * camera["height_px"] / camera["width_px"]))
    changed["version"] += "-wrong"
    return changed


@pytest.mark.parametrize("mistake", [{"mount_height_m": 0.05}, {"mount_height_m": -0.05}, {"hfov_factor": 1.1},
                                     {"hfov_factor": 0.9}], ids=["mount+5cm", "mount-5cm", "fov+10%", "fov-10%"])
def test_a_wrong_mount_height_or_field_of_view_fails_the_fidelity_test(eye_page, world: World, mistake: dict) -> None:
    scene = wrong(scene_dict(convert.scene_to_proto(world.describe_scene())), **mistake)
    worst = 1.0
    for pose in POSES[world.scene.name]:
        server_surfaces, _ = server_view(world, pose)
        ious = mask_ious(server_surfaces, browser_view(eye_page, scene, pose, "surfaces"))
        worst = min(worst, *(value for value in ious.values() if not math.isnan(value)))
    assert worst < MIN_IOU, f"a camera {mistake} off still passed (worst IoU {worst:.3f})"
