"""Records the demo lesson's video from the simulator: a skill server plays the lesson's cues while its camera
frames are piped to ffmpeg (VP8 WebM). Nothing is downloaded; `make run` installs ffmpeg (`make ffmpeg`).

Real-time pacing, so the video's clock is the robot's: what the video shows at t is what a cue at t asks.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

from middleware.lab_runner import LISTENING_LINE, wait_until_serving
from middleware.lessons.commands import RobotCommand
from middleware.lessons.cues import Cue
from middleware.practice.control import CommandTarget, execute
from middleware.robots.link import RobotLink
from middleware.robots.messages import unpack_camera_frame

FPS = 10


def record_demo_video(path: Path, cues: list[Cue], length_s: float) -> bool:
    """Writes path (WebM) showing a fresh robot run through cues; False when ffmpeg is missing."""
    ffmpeg = shutil.which("ffmpeg")
    if ffmpeg is None:
        return False
    path.parent.mkdir(parents=True, exist_ok=True)
    server = subprocess.Popen([sys.executable, "-m", "skill_server", "--port", "0", "--name", "lesson-recorder",
                               "--scene", "lab"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              start_new_session=True)
    try:
        assert server.stdout is not None
        address = ""
        for line in server.stdout:
            match = LISTENING_LINE.search(line)
            if match:
                address = match["address"]
                break
        if not address:
            return False
        threading.Thread(target=server.stdout.read, daemon=True).start()  # keep its pipe drained
        wait_until_serving(address)
        link = RobotLink("lesson-recorder", address, 2.0)
        link.set_controller("recorder")
        _record(link, ffmpeg, path, cues, length_s)
        link.close()
        return path.exists()
    finally:
        server.terminate()
        server.wait(10)


def _record(link: RobotLink, ffmpeg: str, path: Path, cues: list[Cue], length_s: float) -> None:
    latest: list[bytes] = []
    stop = threading.Event()
    subscription = link.camera.subscribe()

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
    sequence = [0]

    def next_sequence() -> int:
        sequence[0] += 1
        return sequence[0]

    target = CommandTarget("lesson-recorder", link, "recorder", next_sequence)
    pending = list(cues)
    active: Cue | None = None
    started = time.monotonic()
    for index in range(int(length_s * FPS)):
        t = index / FPS
        while time.monotonic() - started < t:
            time.sleep(0.005)
        if active is not None and t >= active.end_s:
            execute(target, RobotCommand("stop"), time.perf_counter())
            active = None
        if pending and t >= pending[0].start_s:
            active = pending.pop(0)
            execute(target, active.command, time.perf_counter(), min(10.0, active.end_s - t))
        waited = time.monotonic()
        while not latest and time.monotonic() - waited < 10:
            time.sleep(0.05)
        if latest:
            encoder.stdin.write(latest[0])
    stop.set()
    subscription.close()
    encoder.stdin.close()
    encoder.wait(60)
