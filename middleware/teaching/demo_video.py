"""Records the demo lesson's video from the simulator: a skill server plays the lesson's cues while its camera
frames are piped to ffmpeg (VP8 WebM). Nothing is downloaded; `make run` installs ffmpeg (`make ffmpeg`).

Real-time pacing, so the video's clock is the robot's: what the video shows at t is what a cue at t asks.
"""

from __future__ import annotations

import shutil
import subprocess
import threading
import time
from pathlib import Path

from middleware.access.commands import Commander, owned_robot
from middleware.robots.link import RobotLink
from middleware.robots.messages import unpack_camera_frame
from middleware.robots.processes import SkillServerProcess, SkillServerStartError
from middleware.teaching.command_form import RobotCommand
from middleware.teaching.cues import Cue
from middleware.teaching.targets import execute

FPS = 10


def record_demo_video(path: Path, cues: list[Cue], length_s: float) -> bool:
    """Writes path (WebM) showing a fresh robot run through cues; False when ffmpeg is missing."""
    ffmpeg = shutil.which("ffmpeg")
    if ffmpeg is None:
        return False
    path.parent.mkdir(parents=True, exist_ok=True)
    server = SkillServerProcess("lesson-recorder", "lab", restart=False, echo=False)
    try:
        try:
            address = server.serve()
        except SkillServerStartError:
            return False
        link = RobotLink("lesson-recorder", address, 2.0)
        try:
            _record(owned_robot(link, "recorder"), ffmpeg, path, cues, length_s)
        finally:
            link.close()
        return path.exists()
    finally:
        server.stop(10)


def _record(robot: Commander, ffmpeg: str, path: Path, cues: list[Cue], length_s: float) -> None:
    latest: list[bytes] = []
    stop = threading.Event()
    subscription = robot.link.camera.subscribe()

    def pull() -> None:
        while not stop.is_set():
            message = subscription.next_message(0.5)
            if message is not None:
                latest[:] = [unpack_camera_frame(message)[1]]

    threading.Thread(target=pull, daemon=True).start()
    encoder = subprocess.Popen([ffmpeg, "-loglevel", "error", "-y", "-f", "image2pipe", "-framerate", str(FPS),
                                "-c:v", "mjpeg", "-i", "-", "-c:v", "libvpx", "-b:v", "600k", "-pix_fmt", "yuv420p",
                                str(path)], stdin=subprocess.PIPE)
    assert encoder.stdin is not None
    pending = list(cues)
    active: Cue | None = None
    started = time.monotonic()
    for index in range(int(length_s * FPS)):
        t = index / FPS
        while time.monotonic() - started < t:
            time.sleep(0.005)
        if active is not None and t >= active.end_s:
            execute(robot, RobotCommand("stop"), time.perf_counter())
            active = None
        if pending and t >= pending[0].start_s:
            active = pending.pop(0)
            execute(robot, active.command.motion(), time.perf_counter(), min(10.0, active.end_s - t))
        waited = time.monotonic()
        while not latest and time.monotonic() - waited < 10:
            time.sleep(0.05)
        if latest:
            encoder.stdin.write(latest[0])
    stop.set()
    subscription.close()
    encoder.stdin.close()
    encoder.wait(60)
