"""A plan's prediction ("Try on my practice robot"): the plan run in fast mode on a throwaway simulated copy of the
lab robot, its odometry trace streamed to the page as it grows, then the outcome.

The copy is a robot of the farm started for this request alone (RobotSpec fast: its world steps as fast as the host
allows, not in real time), in the scene the lab robot runs, placed where the lab robot truly stands now (PlaceRobot)
or at its dock, exactly as the practice robot was placed (runs.start_practice_robot). Its plan goes
through access/commands.py under the token the copy was started with. The copy never outlives the request: it is
stopped in the stream's `finally` (a page that goes away closes the stream at the next message), the stream itself
ends after PREDICTION_WALL_S, and a farm robot ends with the process that started it. The outcome comes after
the copy is stopped and the user's slot given back, so a page that reads it may predict again at once.

Everything a person can get wrong is refused before the stream starts, as JSON (the lab robot, the version, the
plan's settings, the cap); what goes wrong once it runs (the farm is full, the copy did not start) is the stream's
last message, {"type": "error", ...}.
"""

from __future__ import annotations

import json
import logging
import math
import secrets
import threading
import time
from collections.abc import Callable, Generator, Iterator
from contextlib import suppress
from dataclasses import dataclass, field

from flask import Flask
from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.access.commands import owned_robot
from middleware.errors import ApiError, Refused, written_number
from middleware.farm.base import FarmUnavailable, RobotFarm, RobotSpec
from middleware.plans.language import plan_from_json
from middleware.plans.proto_form import plan_to_proto
from middleware.plans.runs import LabRobotNow, start_practice_robot
from middleware.robots.link import CommandRefused, RobotLink, RobotUnavailable
from middleware.robots.messages import FINAL_GOAL_STATUSES, goal_dict
from middleware.teaching.targets import skill_schemas
from protos.telelab.v1 import robot_pb2

log = logging.getLogger(__name__)
_EXTENSION_KEY = "telelab.predictions"

PREDICTION_WALL_S = 120.0  # the stream ends, and the copy stops, after this long whatever the plan does
PROGRESS_PERIOD_S = 0.1  # how often the page hears the line running and the trace's new points
TRACE_RATE_HZ = 50.0  # odometry samples per second of sim time (the most StreamTelemetry sends)
TRACE_STEP_M = 0.01  # a trace point once the robot moved 1 cm
MAX_TRACE_POINTS = 5000
PREDICTION_PREFIX = "predict-"


@dataclass(frozen=True)
class PredictionRequest:
    """What a prediction runs: whose, which plan, in which scene, beside which lab robot and from where."""

    user_id: int
    plan_name: str
    document: dict[str, object]
    scene: str
    beside: LabRobotNow | None
    from_dock: bool


@dataclass
class PredictionSlots:
    """This process's predictions: at most cap at once (each steps a world flat out, a core), one per user."""

    cap: int
    _running: set[int] = field(default_factory=set)
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def check(self, user_id: int) -> None:
        """A 409 when user_id has a prediction running here or the process runs as many as it may."""
        with self._lock:
            self._refusal(user_id)

    def take(self, user_id: int) -> None:
        """Holds a slot for user_id (refused as check() is)."""
        with self._lock:
            self._refusal(user_id)
            self._running.add(user_id)

    def release(self, user_id: int) -> None:
        """Gives user_id's slot back."""
        with self._lock:
            self._running.discard(user_id)

    def _refusal(self, user_id: int) -> None:
        if user_id in self._running:
            raise ApiError(409, "busy", gettext("A prediction of yours is running already: wait for its outcome."))
        if len(self._running) >= self.cap:
            raise ApiError(409, "busy", gettext("The lab is predicting as many plans as it can right now. Try again "
                                                "in a few seconds."))


def prediction_slots(app: Flask) -> PredictionSlots:
    """The prediction slots of app (made at the first prediction, from PREDICTION_CAP)."""
    slots = app.extensions.get(_EXTENSION_KEY)
    if slots is None:
        slots = app.extensions.setdefault(_EXTENSION_KEY, PredictionSlots(int(app.config.get("PREDICTION_CAP", 2))))
    return slots


def add_trace_point(points: list[dict[str, float]], x_m: float, y_m: float, theta_rad: float) -> None:
    """Adds a pose to a trace: its newest point moves with the robot until it is TRACE_STEP_M from the one before
    it, then stays, and the next pose starts a new point (a robot at rest adds nothing); at most MAX_TRACE_POINTS,
    the last one following the robot. A pose that is not finite is left out."""
    point = {"x_m": round(x_m, 4), "y_m": round(y_m, 4), "theta_rad": round(theta_rad, 4)}
    if not all(math.isfinite(v) for v in point.values()):
        return
    floating = len(points) >= 2 and math.hypot(points[-1]["x_m"] - points[-2]["x_m"],
                                               points[-1]["y_m"] - points[-2]["y_m"]) < TRACE_STEP_M
    if floating or len(points) >= MAX_TRACE_POINTS:
        points[-1] = point
    else:
        points.append(point)


class TraceRecorder:
    """The copy's odometry poses, read from a pose-only telemetry stream of its own on a thread of its own."""

    def __init__(self, link: RobotLink) -> None:
        self._stream = link.stream_poses(TRACE_RATE_HZ)
        self._lock = threading.Lock()
        self._points: list[dict[str, float]] = []
        self._thread = threading.Thread(target=self._read, name=f"trace-{link.name}", daemon=True)
        self._thread.start()

    def _read(self) -> None:
        with suppress(Exception):  # the stream ends when the copy stops or the recorder closes it
            for message in self._stream:
                self.add(message.odometry.pose)

    def add(self, pose: robot_pb2.Pose2D) -> None:
        """Adds a pose to the trace (add_trace_point)."""
        with self._lock:
            add_trace_point(self._points, pose.x_m, pose.y_m, pose.theta_rad)

    def points(self) -> list[dict[str, float]]:
        """The trace so far."""
        with self._lock:
            return list(self._points)

    def close(self) -> None:
        """Stops reading."""
        with suppress(Exception):
            self._stream.cancel()
        self._thread.join(2.0)


@dataclass
class PredictionCopy:
    """The throwaway robot a prediction runs on and what reads it, as far as they got started."""

    farm: RobotFarm
    name: str
    started: bool = False
    link: RobotLink | None = None
    recorder: TraceRecorder | None = None

    def stop(self) -> None:
        """Stops reading the copy and stops the copy (a start that failed half-way may have left it)."""
        if self.recorder is not None:
            self.recorder.close()
        if self.link is not None:
            self.link.close()
        try:
            if self.started or self.farm.find(self.name) is not None:
                self.farm.stop(self.name)
        except FarmUnavailable as error:
            log.warning("the prediction robot %s was not stopped: %s", self.name, error)


def run_prediction(farm: RobotFarm, slots: PredictionSlots, request: PredictionRequest
                   ) -> Generator[dict[str, object], None, None]:
    """The prediction's messages: progress while the copy starts and the plan runs, then the end (or an error).

    The outcome is the last message, sent once the copy is stopped and the user's slot given back: a page that reads
    it may predict again at once. The copy is stopped whether the plan ended, the page went away (the generator is
    closed) or something failed.
    """
    try:
        slots.take(request.user_id)
    except ApiError as refused:
        yield {"type": "error", **refused.to_dict()}
        return
    copy = PredictionCopy(farm, f"{PREDICTION_PREFIX}{secrets.token_hex(6)}")
    try:
        outcome = yield from _predict(copy, request)
    except Refused as refused:  # the robot refused or away, the farm full or away, the plan invalid on the copy
        outcome = {"type": "error", **refused.to_dict()}
    finally:
        slots.release(request.user_id)  # the prediction is over: the copy's stopping no longer holds the user back
        copy.stop()
    yield outcome


def _predict(copy: PredictionCopy, request: PredictionRequest
             ) -> Generator[dict[str, object], None, dict[str, object]]:
    """Starts the copy, runs the plan on it and follows it: progress messages; returns the outcome's message."""
    token = secrets.token_urlsafe(32)
    starting = (gettext("Starting a simulated copy of %(robot)s in the scene %(scene)s…", robot=request.beside.name,
                        scene=request.scene) if request.beside
                else gettext("Starting a simulated copy in the scene %(scene)s…", scene=request.scene))
    yield {"type": "progress", "phase": "starting", "message": starting}
    robot = copy.farm.start(RobotSpec(copy.name, request.scene, token, fast=True))
    copy.started = True
    link = copy.link = RobotLink(copy.name, robot.address, rpc_timeout_s=5.0)
    owned = owned_robot(link, token)
    plan = plan_from_json(request.document, skill_schemas(link, motor_only=True))
    start = start_practice_robot(owned, request.from_dock, request.beside)
    recorder = copy.recorder = TraceRecorder(link)
    begun = time.monotonic()
    goal = owned.run_plan(request.plan_name, plan_to_proto(plan), preempt=True)
    yield {"type": "started", "start": start, "goal": goal_dict(goal)}
    final = yield from _follow(owned.goal_state, goal.goal_id, recorder, begun)
    if final is None:
        with suppress(CommandRefused, RobotUnavailable):
            owned.cancel(goal.goal_id)
        too_long = ApiError(409, "prediction_too_long", gettext(
            "The prediction ran past %(seconds)s s and was stopped: shorten the plan, or run it on the lab robot.",
            seconds=written_number(PREDICTION_WALL_S, ".0f")))
        return {"type": "error", **too_long.to_dict(), "trace": recorder.points()}
    recorder.add(link.odometry_pose())  # where it came to rest: the end point the lab run is compared with
    return {"type": "end", "goal": goal_dict(final), "trace": recorder.points(), "start": start,
            "wall_s": round(time.monotonic() - begun, 3),
            "sim_time_s": round(final.ended_sim_s - final.accepted_sim_s, 3)}  # the plan's time, predicted


def prediction_stream(farm: RobotFarm, slots: PredictionSlots, request: PredictionRequest) -> Iterator[bytes]:
    """run_prediction's messages as JSON lines."""
    messages = run_prediction(farm, slots, request)
    try:
        for message in messages:
            yield json.dumps(message, allow_nan=False).encode() + b"\n"
    finally:
        messages.close()  # the page went away: the copy stops now, not when the generator is collected


def _follow(goal_state: Callable[[str], robot_pb2.GoalState], goal_id: str, recorder: TraceRecorder, begun: float
            ) -> Generator[dict[str, object], None, robot_pb2.GoalState | None]:
    """Progress messages (the line running, the trace's new points) until the goal ends; its final state, or None
    when the wall-time bound passed first. A generator whose return value is the final state."""
    sent = 0
    while time.monotonic() - begun < PREDICTION_WALL_S:
        state = goal_state(goal_id)
        answer = goal_dict(state)
        if answer["status"] in FINAL_GOAL_STATUSES:
            return state
        points = recorder.points()
        feedback = answer.get("feedback") if isinstance(answer.get("feedback"), dict) else {}
        assert isinstance(feedback, dict)
        # From the last point sent on: it may have moved since (the robot crept less than a trace step).
        since = max(0, sent - 1)
        yield {"type": "progress", "phase": "running", "feedback": feedback, "trace_from": since,
               "trace": points[since:]}
        sent = len(points)
        time.sleep(PROGRESS_PERIOD_S)
    return None
