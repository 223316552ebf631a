"""Stand-alone dev harness for client_ui. NOT part of the product.

It renders the real templates with fake context (a fake current_user, csrf_token() == "dev") and
serves fake robot sockets (camera, telemetry, drive) with the same message shapes as the middleware,
so the pages can be looked at and clicked without the middleware or a skill server. Nothing here is
a model for the real middleware: there is no real authentication, no CSRF check and no lease.

Run:  .venv/bin/python client_ui/dev_server.py [--port 5050]   then open http://127.0.0.1:5050/
Log in as student / student (or tutor / tutor).
"""

from __future__ import annotations

import argparse
import json
import math
import struct
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import simplejpeg
from flask import (
    Blueprint,
    Flask,
    flash,
    jsonify,
    redirect,
    render_template,
    request,
    session,
    url_for,
)
from flask_sock import Sock

from middleware.serve import quiet_websocket_endings

HERE = Path(__file__).resolve().parent
USERS = {"student": ("student", "student"), "tutor": ("tutor", "tutor")}  # name -> (password, role)
MAX_LINEAR_MPS = 0.5
MAX_ANGULAR_RADPS = 1.5
DEADMAN_TIMEOUT_S = 0.4
CAMERA_WIDTH_PX, CAMERA_HEIGHT_PX, CAMERA_HFOV_DEG = 320, 240, 60
CAMERA_FPS = 15
TELEMETRY_HZ = 10
SEND_INTERVAL_MS = 50

# Bumped by /dev/kick: every open fake socket then closes with 1012 so the client's reconnect shows.
_kick_generation = 0


@dataclass
class FakeRobot:
    """A point robot that integrates the last drive command and stops when commands stop."""

    name: str
    title: str
    online: bool
    x_m: float = 0.0
    y_m: float = 0.0
    theta_rad: float = 0.0
    linear_mps: float = 0.0
    angular_radps: float = 0.0
    last_applied_sequence: int = 0
    last_command_s: float = 0.0
    deadman_stopped: bool = False
    tick: int = 0
    lock: threading.Lock = field(default_factory=threading.Lock)

    def command(self, sequence: int, linear_mps: float, angular_radps: float) -> None:
        """Apply a drive command (already validated)."""
        with self.lock:
            self.linear_mps, self.angular_radps = linear_mps, angular_radps
            self.last_applied_sequence = sequence
            self.last_command_s = time.monotonic()
            self.deadman_stopped = False

    def step(self, dt_s: float) -> None:
        """Advance the pose by dt_s; the deadman zeroes the speeds when commands stop."""
        with self.lock:
            self.tick += 1
            moving = self.linear_mps != 0 or self.angular_radps != 0
            if moving and time.monotonic() - self.last_command_s > DEADMAN_TIMEOUT_S:
                self.linear_mps = self.angular_radps = 0.0
                self.deadman_stopped = True
            self.theta_rad = math.remainder(self.theta_rad + self.angular_radps * dt_s, math.tau)
            self.x_m += self.linear_mps * math.cos(self.theta_rad) * dt_s
            self.y_m += self.linear_mps * math.sin(self.theta_rad) * dt_s

    def snapshot(self) -> dict[str, Any]:
        """A consistent copy of the state for one message."""
        with self.lock:
            return {
                "tick": self.tick,
                "pose": {"x_m": self.x_m, "y_m": self.y_m, "theta_rad": self.theta_rad},
                "linear_mps": self.linear_mps,
                "angular_radps": self.angular_radps,
                "last_applied_sequence": self.last_applied_sequence,
                "deadman_stopped": self.deadman_stopped,
            }


ROBOTS = {
    "lab-1": FakeRobot("lab-1", "Lab robot 1", online=True),
    "lab-2": FakeRobot("lab-2", "Lab robot 2", online=False),
}


class FakeUser:
    """Stands in for flask_login's current_user."""

    def __init__(self, username: str | None) -> None:
        self.username = username or ""
        self.role = USERS[username][1] if username in USERS else ""
        self.is_authenticated = username in USERS


def _panorama() -> np.ndarray:
    """A 360° strip (sky, floor, coloured posts) that the fake camera pans across as the robot turns."""
    width = CAMERA_WIDTH_PX * 360 // CAMERA_HFOV_DEG
    image = np.zeros((CAMERA_HEIGHT_PX, width, 3), np.uint8)
    horizon = CAMERA_HEIGHT_PX // 2
    sky = np.linspace([150, 190, 235], [225, 235, 245], horizon)
    floor = np.linspace([150, 150, 145], [95, 95, 90], CAMERA_HEIGHT_PX - horizon)
    image[:horizon] = sky[:, None, :].astype(np.uint8)
    image[horizon:] = floor[:, None, :].astype(np.uint8)
    colours = [(220, 60, 50), (240, 170, 30), (60, 160, 80), (40, 110, 210), (150, 70, 190), (30, 170, 170)]
    for index in range(12):
        left = index * width // 12 + 40
        colour = colours[index % len(colours)]
        image[horizon - 60 : horizon + 50, left : left + 34] = colour
        image[horizon - 60 : horizon - 52, left : left + 34] = 255
    return image


PANORAMA = _panorama()


def camera_jpeg(pose: dict[str, float], frame_sequence: int) -> bytes:
    """The view for a heading, with a blinking corner mark so a frozen stream is obvious."""
    px_per_rad = CAMERA_WIDTH_PX / math.radians(CAMERA_HFOV_DEG)
    offset = int(-pose["theta_rad"] * px_per_rad) % PANORAMA.shape[1]
    columns = (np.arange(CAMERA_WIDTH_PX) + offset) % PANORAMA.shape[1]
    frame = np.ascontiguousarray(PANORAMA[:, columns])
    bar = frame_sequence % CAMERA_WIDTH_PX
    frame[-6:, : bar + 1] = (255, 255, 255)
    return simplejpeg.encode_jpeg(frame, quality=80, colorspace="RGB")


def camera_packet(robot: FakeRobot, frame_sequence: int) -> bytes:
    """4-byte big-endian header length, JSON header, JPEG."""
    state = robot.snapshot()
    capture_s = time.time() - 0.02
    jpeg = camera_jpeg(state["pose"], frame_sequence)
    header = json.dumps({
        "frame_sequence": frame_sequence,
        "capture_unix_s": capture_s,
        "sent_unix_s": time.time(),
        "last_applied_sequence": state["last_applied_sequence"],
        "pose_at_capture": state["pose"],
        "width_px": CAMERA_WIDTH_PX,
        "height_px": CAMERA_HEIGHT_PX,
    }).encode()
    return struct.pack(">I", len(header)) + header + jpeg


def telemetry_message(robot: FakeRobot) -> str:
    """One telemetry JSON message."""
    state = robot.snapshot()
    return json.dumps({
        "type": "telemetry",
        "tick": state["tick"],
        "sim_time_s": state["tick"] / 50,
        "capture_unix_s": time.time(),
        "last_applied_sequence": state["last_applied_sequence"],
        "deadman_stopped": state["deadman_stopped"],
        "odometry": {
            "pose": state["pose"],
            "linear_mps": state["linear_mps"],
            "angular_radps": state["angular_radps"],
        },
        "sonar": {"ranges_m": [2.0] * 8},
        "laser": {"angle_min_rad": -math.pi / 2, "angle_increment_rad": math.pi / 180, "ranges_m": [3.0] * 181},
    })


def error_message(code: str, message: str, field_name: str | None = None) -> str:
    """The error shape every socket uses."""
    return json.dumps({"type": "error", "code": code, "message": message, "field": field_name})


def _robot_loop(stop: threading.Event) -> None:
    dt_s = 0.02
    while not stop.wait(dt_s):
        for robot in ROBOTS.values():
            robot.step(dt_s)


def close_socket(ws: Any, code: int, reason: str) -> None:
    """Close with one of the server's close codes."""
    ws.close(code, reason)


def _socket_guard(ws: Any, robot_name: str) -> FakeRobot | None:
    """Close with the server's codes when the user or robot is wrong; else the robot."""
    if session.get("user") not in USERS:
        close_socket(ws, 4401, "not logged in")
        return None
    robot = ROBOTS.get(robot_name)
    if robot is None:
        close_socket(ws, 4404, "unknown robot")
        return None
    return robot


def _kicked(generation: int) -> bool:
    return generation != _kick_generation


def create_app() -> Flask:
    """The dev app: real templates and static files, fake everything else."""
    app = Flask(
        __name__,
        template_folder=str(HERE / "templates"),
        static_folder=str(HERE / "static"),
        static_url_path="/static",
    )
    app.secret_key = "dev-only-not-secret"
    app.config["SEND_FILE_MAX_AGE_DEFAULT"] = 0
    app.config["TEMPLATES_AUTO_RELOAD"] = True
    sock = Sock(app)
    app.wsgi_app = quiet_websocket_endings(app.wsgi_app)  # type: ignore[method-assign]

    @app.context_processor
    def fake_context() -> dict[str, Any]:
        return {"current_user": FakeUser(session.get("user")), "csrf_token": lambda: "dev"}

    auth = Blueprint("auth", __name__)
    lab = Blueprint("lab", __name__)

    @auth.route("/login", methods=["GET", "POST"])
    def login() -> Any:
        next_url = request.values.get("next") or None
        if request.method == "POST":
            username = request.form.get("username", "").strip()
            password = request.form.get("password", "")
            if USERS.get(username, (None,))[0] == password:
                session["user"] = username
                flash(f"Welcome, {username}.", "success")
                return redirect(next_url if next_url and next_url.startswith("/") else url_for("lab.index"))
            return render_template(
                "login.html", error="Wrong username or password.", username=username, next_url=next_url
            ), 401
        return render_template("login.html", error=None, username="", next_url=next_url)

    @auth.route("/logout", methods=["POST"])
    def logout() -> Any:
        session.pop("user", None)
        flash("You have logged out.", "info")
        return redirect(url_for("auth.login"))

    def login_required() -> Any:
        if session.get("user") not in USERS:
            return redirect(url_for("auth.login", next=request.path))
        return None

    @lab.route("/lab/")
    def index() -> Any:
        return login_required() or render_template("lab_index.html", robots=list(ROBOTS.values()))

    @lab.route("/lab/<robot_name>")
    def console(robot_name: str) -> Any:
        if redirect_response := login_required():
            return redirect_response
        robot = ROBOTS.get(robot_name)
        if robot is None:
            return render_template(
                "error.html", title="No such robot", message=f"There is no robot called “{robot_name}”."
            ), 404
        return render_template("console.html", robot_name=robot.name, robot_title=robot.title)

    app.register_blueprint(auth)
    app.register_blueprint(lab)

    @app.route("/")
    def home() -> Any:
        return redirect(url_for("lab.index"))

    @app.errorhandler(404)
    def not_found(_error: Exception) -> Any:
        return render_template(
            "error.html", title="Page not found", message="That page does not exist. Check the address."
        ), 404

    @app.route("/dev/kick", methods=["GET", "POST"])
    def kick() -> Any:
        global _kick_generation
        _kick_generation += 1
        return jsonify({"generation": _kick_generation})

    @app.route("/api/robots/<robot_name>")
    def robot_info(robot_name: str) -> Any:
        if session.get("user") not in USERS:
            return jsonify({"error": {"code": "not_logged_in", "message": "Log in first.", "field": None}}), 401
        robot = ROBOTS.get(robot_name)
        if robot is None:
            message = f"There is no robot called {robot_name}."
            return jsonify({"error": {"code": "unknown_robot", "message": message, "field": None}}), 404
        info = {
            "max_linear_mps": MAX_LINEAR_MPS,
            "max_angular_radps": MAX_ANGULAR_RADPS,
            "deadman_timeout_s": DEADMAN_TIMEOUT_S,
            "camera_width_px": CAMERA_WIDTH_PX,
            "camera_height_px": CAMERA_HEIGHT_PX,
            "camera_hfov_deg": CAMERA_HFOV_DEG,
        }
        return jsonify({
            "name": robot.name, "title": robot.title, "online": robot.online,
            "info": info if robot.online else None,
        })

    @sock.route("/ws/robots/<robot_name>/camera")
    def camera_socket(ws: Any, robot_name: str) -> None:
        robot = _socket_guard(ws, robot_name)
        if robot is None:
            return
        generation = _kick_generation
        if not robot.online:
            ws.send(json.dumps({"type": "status", "robot_online": False, "message": f"{robot.title} is offline."}))
        sequence = 0
        while ws.connected and not _kicked(generation):
            if robot.online:
                sequence += 1
                ws.send(camera_packet(robot, sequence))
            time.sleep(1 / CAMERA_FPS)
        if _kicked(generation):
            close_socket(ws, 1012, "server restarting")

    @sock.route("/ws/robots/<robot_name>/telemetry")
    def telemetry_socket(ws: Any, robot_name: str) -> None:
        robot = _socket_guard(ws, robot_name)
        if robot is None:
            return
        generation = _kick_generation
        if not robot.online:
            ws.send(json.dumps({"type": "status", "robot_online": False, "message": f"{robot.title} is offline."}))
        while ws.connected and not _kicked(generation):
            if robot.online:
                ws.send(telemetry_message(robot))
            time.sleep(1 / TELEMETRY_HZ)
        if _kicked(generation):
            close_socket(ws, 1012, "server restarting")

    @sock.route("/ws/robots/<robot_name>/drive")
    def drive_socket(ws: Any, robot_name: str) -> None:
        robot = _socket_guard(ws, robot_name)
        if robot is None:
            return
        if not robot.online:
            ws.send(error_message("robot_offline", f"{robot.title} is offline; driving is not possible."))
            close_socket(ws, 1011, "robot offline")
            return
        generation = _kick_generation
        ws.send(json.dumps({
            "type": "ready", "max_linear_mps": MAX_LINEAR_MPS,
            "max_angular_radps": MAX_ANGULAR_RADPS, "send_interval_ms": SEND_INTERVAL_MS,
        }))
        last_sequence = 0
        while ws.connected and not _kicked(generation):
            text = ws.receive(timeout=0.2)
            if text is None:
                continue
            try:
                message = json.loads(text)
                sequence = int(message["sequence"])
                kind = message["type"]
            except (ValueError, KeyError, TypeError):
                ws.send(error_message("bad_message", "Send JSON with type and sequence."))
                continue
            if sequence <= last_sequence:
                ws.send(error_message("stale_sequence", "Sequence numbers must increase.", "sequence"))
                continue
            last_sequence = sequence
            if kind == "stop":
                linear, angular = 0.0, 0.0
            elif kind == "drive":
                linear = float(message.get("linear_mps", 0))
                angular = float(message.get("angular_radps", 0))
                if not (math.isfinite(linear) and abs(linear) <= MAX_LINEAR_MPS):
                    ws.send(error_message("out_of_range", "Linear speed is out of range.", "linear_mps"))
                    continue
                if not (math.isfinite(angular) and abs(angular) <= MAX_ANGULAR_RADPS):
                    ws.send(error_message("out_of_range", "Turn rate is out of range.", "angular_radps"))
                    continue
            else:
                ws.send(error_message("bad_message", f"Unknown message type {kind!r}.", "type"))
                continue
            robot.command(sequence, linear, angular)
            ws.send(json.dumps({
                "type": "ack", "sequence": sequence, "applied_sequence": sequence,
                "linear_mps": linear, "angular_radps": angular,
            }))
        if _kicked(generation):
            close_socket(ws, 1012, "server restarting")

    stop = threading.Event()
    threading.Thread(target=_robot_loop, args=(stop,), daemon=True, name="fake-robots").start()
    app.extensions["dev_robot_loop_stop"] = stop
    return app


def main() -> None:
    """Run the harness with Flask's threaded dev server."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=5050)
    args = parser.parse_args()
    create_app().run(host=args.host, port=args.port, threaded=True, debug=False)


if __name__ == "__main__":
    main()
