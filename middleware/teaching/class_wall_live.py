"""The class wall's channels: one socket carries the whole class to the tutor, one its own seat to each student.

`/ws/courses/<id>/class-wall` (the course's tutors and admins): the seats (names, hands, takeovers, tests) whenever
they change, and every robot's pose, speed, battery and activity in one message POSE_PERIOD_S apart, taken from
the robot's telemetry hub (robots/fanout.py: one upstream per robot per process, shared with the consoles), never
one socket per tile. Who is running a skill or a plan is asked of each robot every GOALS_EVERY_S. While the wall
is open its tutor's takeovers hold (class_wall.still_watching); when it closes they end, unless the worker is
restarting (the wall reconnects to another worker and holds them again).

`/ws/class-session/wall` (a student with a seat): their hand, who holds their robot and the tutor's notices,
whenever they change. Both are woken by the event bus (topic "class-wall") in every worker at once, and read the
database again every SEATS_EVERY_S besides (a test that starts, a robot that stops).
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
import time
from collections.abc import Callable
from typing import Any

from flask import current_app
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user
from sqlalchemy.orm import Session

from middleware import events
from middleware.access.commands import RobotCommands, robot_commands
from middleware.chat.sockets import room_channel
from middleware.db import get_session, unit_of_work
from middleware.errors import Refused
from middleware.live.loop import Continuation, blocking_work, channel_loop
from middleware.live.wire import LiveSocket
from middleware.models import User
from middleware.models.farm import ClassSession
from middleware.realtime import CLOSE_FORBIDDEN, CLOSE_NOT_FOUND, Channels, WebSocket, as_json, refuse
from middleware.robots.fanout import FanoutHub, Subscription
from middleware.robots.link import RobotLink
from middleware.robots.refusals import RobotUnavailable
from middleware.teaching import class_sessions, class_wall
from middleware.validation import decimal_int
from protos.telelab.v1 import robot_pb2

POSE_PERIOD_S = 0.2  # 5 poses a second per robot: smooth enough to see a robot move, light for 200 of them
SEATS_EVERY_S = 2.0
GOALS_EVERY_S = 3.0
MOVING_MPS, TURNING_RADPS = 0.01, 0.02

_lock = threading.Lock()
_versions: dict[int, int] = {}
_wakers: dict[int, set[Callable[[], None]]] = {}
_listening_engines: set[int] = set()


def notify(class_session_id: int | None) -> None:
    """Wakes the sockets of the class session (None: every one)."""
    with _lock:
        ids = list(_wakers) if class_session_id is None else [class_session_id]
        wakers: list[Callable[[], None]] = []
        for session_id in ids:
            _versions[session_id] = _versions.get(session_id, 0) + 1
            wakers.extend(_wakers.get(session_id, ()))
    for wake in wakers:
        wake()


def _heard(key: str | None) -> None:
    notify(None if key is None else decimal_int(key, 1))


def _listen(db: Session) -> None:
    engine = db.get_bind().engine
    if id(engine) not in _listening_engines:
        _listening_engines.add(id(engine))
        events.listen(engine, class_wall.TOPIC, _heard)


class _Wake:
    """A socket's registration for its class session's news."""

    def __init__(self, class_session_id: int, live: LiveSocket) -> None:
        loop = asyncio.get_running_loop()
        self.class_session_id = class_session_id

        def wake() -> None:
            with contextlib.suppress(RuntimeError):  # the loop closed: the process is ending
                loop.call_soon_threadsafe(live.nudge)

        self._wake = wake
        with _lock:
            _wakers.setdefault(class_session_id, set()).add(wake)

    def version(self) -> int:
        return _versions.get(self.class_session_id, 0)

    def leave(self) -> None:
        with _lock:
            _wakers.get(self.class_session_id, set()).discard(self._wake)


def _read_wall(class_session_id: int, tutor_id: int, refresh: bool) -> list[dict[str, object]] | None:
    """The wall's seats (None once the session ended); refresh: the tutor's takeovers hold on."""
    with unit_of_work(current_app) as db:
        opened = db.get(ClassSession, class_session_id)
        if opened is None or opened.ended_at is not None:
            return None
        if refresh:
            class_wall.still_watching(db, class_session_id, tutor_id)
        return [seat.to_dict() for seat in class_wall.wall_seats(db, class_session_id)]


def _tutor_left(class_session_id: int, tutor_id: int) -> None:
    with unit_of_work(current_app) as db:
        class_wall.tutor_left(db, class_session_id, tutor_id)


def activity(goals: list[Any]) -> str:
    """What a robot's running goals say it does: "plan:<name>", "skill:<name>", "driving" or ""."""
    running = [goal for goal in goals if not goal.ended_sim_s]
    for goal in running:
        if goal.skill.startswith("plan:"):
            return goal.skill
    for goal in running:
        if goal.skill != "direct_control":
            return f"skill:{goal.skill}"
    return "driving" if running else ""


def _goals_of(links: dict[int, RobotLink], online: Callable[[int], bool]) -> dict[int, str]:
    """Each robot's activity from its goals (one call each, in turn; a robot whose stream is down is not asked)."""
    found = {}
    for user_id, link in links.items():
        if not online(user_id):
            found[user_id] = "faulted"
            continue
        try:
            found[user_id] = activity(link.goals())
        except RobotUnavailable:
            found[user_id] = "faulted"
    return found


def pose_row(user_id: int, telemetry: Any, goal_activity: str, online: bool) -> list[object] | None:
    """[user id, x, y, theta, linear, angular, battery charge, activity] from the robot's telemetry message as it
    came (read here in a few fields: the wall never packs a message it does not send whole)."""
    if not isinstance(telemetry, robot_pb2.Telemetry):
        return None
    odometry = telemetry.odometry
    pose, linear, angular = odometry.pose, odometry.linear_mps, odometry.angular_radps
    charge = telemetry.battery.charge
    if not online:
        state = "faulted"
    elif goal_activity and goal_activity != "driving":
        state = goal_activity
    elif abs(linear) > MOVING_MPS or abs(angular) > TURNING_RADPS:
        state = "driving"
    else:
        state = "idle"
    return [user_id, round(pose.x_m, 3), round(pose.y_m, 3), round(pose.theta_rad, 3), round(linear, 3),
            round(angular, 3), round(charge, 3), state]


class _Robots:
    """The wall's subscriptions to its robots, following the seats. A robot whose whole telemetry this worker pumps
    anyway (a console here watches it) is read from that hub; any other from its poses hub (pose, speeds, battery,
    POSES_HZ a second): the wall alone never pulls 181 laser ranges ten times a second of a robot whose console is
    on another worker."""

    def __init__(self, tutor_id: int, commands: RobotCommands) -> None:
        self._tutor_id = tutor_id
        self._commands = commands
        self.links: dict[int, RobotLink] = {}
        self._subscriptions: dict[int, tuple[FanoutHub[Any], Subscription[Any]]] = {}
        self.rows: dict[int, list[object]] = {}
        self.activities: dict[int, str] = {}

    def find(self, seats: list[dict[str, object]]) -> dict[int, RobotLink | None]:
        """The link of every running seat's robot not followed yet (None: not reachable now); it may read the
        database, so it runs on the pool."""
        wanted = {int(str(seat["user_id"])): str(seat["robot"]) for seat in seats if seat["seat_state"] == "ready"}
        return {user_id: self._commands.reachable(robot, self._tutor_id) for user_id, robot in wanted.items()
                if user_id not in self.links or self.links[user_id].name != robot}

    def follow(self, seats: list[dict[str, object]], found: dict[int, RobotLink | None]) -> None:
        """Subscribes to the robots found, and leaves those of seats no longer running (on the loop)."""
        running = {int(str(seat["user_id"])) for seat in seats if seat["seat_state"] == "ready"}
        for user_id in list(self.links):
            if user_id not in running or user_id in found:
                self._leave(user_id)
        for user_id, link in found.items():
            if link is None or link.telemetry.closed:
                continue
            self.links[user_id] = link
            self._read_from(user_id, self._source(link, None))

    @staticmethod
    def _source(link: RobotLink, current: FanoutHub[Any] | None) -> FanoutHub[Any]:
        """The hub to read the robot from: its telemetry while someone else in this worker watches that."""
        others = link.telemetry.viewer_count - (1 if current is link.telemetry else 0)
        return link.telemetry if others > 0 else link.poses

    def _read_from(self, user_id: int, hub: FanoutHub[Any]) -> None:
        held = self._subscriptions.get(user_id)
        if held is not None and held[0] is hub:
            return
        with contextlib.suppress(RuntimeError):  # the hub closed: the application is ending
            self._subscriptions[user_id] = (hub, hub.subscribe())
            if held is not None:
                held[1].close()

    def _leave(self, user_id: int) -> None:
        self.links.pop(user_id, None)
        self.rows.pop(user_id, None)
        held = self._subscriptions.pop(user_id, None)
        if held is not None:
            held[1].close()

    def online(self, user_id: int) -> bool:
        """Whether the robot's stream the wall reads is delivering."""
        held = self._subscriptions.get(user_id)
        return held is None or held[0].status_with_version()[0].online

    def poses(self) -> list[list[object]]:
        """Every followed robot's newest row (the last one again for a robot with nothing new)."""
        for user_id, (hub, subscription) in list(self._subscriptions.items()):
            telemetry = subscription.next_item(0)
            online = hub.status_with_version()[0].online
            if telemetry is not None:
                row = pose_row(user_id, telemetry, self.activities.get(user_id, ""), online)
                if row is not None:
                    self.rows[user_id] = row
            elif user_id in self.rows and not online:
                self.rows[user_id][-1] = "faulted"
            self._read_from(user_id, self._source(self.links[user_id], hub))
        return list(self.rows.values())

    def take_activities(self, done: asyncio.Future[dict[int, str]]) -> None:
        """The goals' answer, once it came (a cancelled or failed ask keeps the last)."""
        if not done.cancelled() and done.exception() is None:
            self.activities = done.result()

    def close(self) -> None:
        """Leaves every hub."""
        for user_id in list(self.links):
            self._leave(user_id)


def _refusal_close(ws: WebSocket, refused: Refused) -> None:
    refuse(ws, CLOSE_NOT_FOUND if refused.status == 404 else CLOSE_FORBIDDEN, refused.code, refused.message,
           refused.field)


def wall_channel(ws: WebSocket, course_id: int) -> Continuation | None:
    """The whole class for its tutor: seats when they change, every robot's pose POSE_PERIOD_S apart."""
    tutor_id = int(current_user.get_id())
    db = get_session()
    actor = db.get(User, tutor_id)
    try:
        if actor is None:
            raise Refused(403, "forbidden", gettext("Log in again."))
        _course, opened = class_wall.wall_session(db, actor, course_id)
    except Refused as refused:
        _refusal_close(ws, refused)
        return None
    class_session_id = opened.id
    _listen(db)
    db.close()  # a socket lives long: no transaction stays open between reads
    work = blocking_work()
    robots = _Robots(tutor_id, robot_commands())

    async def follow(live: LiveSocket) -> None:
        wake = _Wake(class_session_id, live)
        read_version, sent_seats = -1, None
        seats_at = goals_at = refreshed_at = poses_at = 0.0
        goals: asyncio.Future[dict[int, str]] | None = None
        try:
            while live.connected:
                now = time.monotonic()
                if wake.version() != read_version or now - seats_at >= SEATS_EVERY_S:
                    read_version, seats_at = wake.version(), now
                    refresh = now - refreshed_at >= class_wall.TAKEOVER_REFRESH_S
                    seats = await work(_read_wall, class_session_id, tutor_id, refresh)
                    if refresh:
                        refreshed_at = now
                    if seats is None:
                        await live.send(as_json({"type": "ended"}))
                        break
                    robots.follow(seats, await work(robots.find, seats))
                    if seats != sent_seats:
                        await live.send(as_json({"type": "seats", "seats": seats}))
                        sent_seats = seats
                if now - goals_at >= GOALS_EVERY_S and robots.links and (goals is None or goals.done()):
                    goals_at = now  # asked beside the poses: a robot slow to answer never holds them back
                    goals = asyncio.ensure_future(work(_goals_of, dict(robots.links), robots.online))
                    goals.add_done_callback(lambda done: robots.take_activities(done))
                if now - poses_at >= POSE_PERIOD_S:
                    poses_at = now
                    live.send_latest(as_json({"type": "poses", "t": round(time.time(), 3),
                                              "robots": robots.poses()}))
                wait_s = max(0.0, POSE_PERIOD_S - (time.monotonic() - poses_at))
                await live.receive(timeout=wait_s)  # woken by notify(); what the page sends is dropped
        finally:
            wake.leave()
            if goals is not None:
                goals.cancel()
            robots.close()
            if not channel_loop().draining:  # a restarting worker's wall comes back on another: keep holding
                await work(_tutor_left, class_session_id, tutor_id)

    return follow


def _read_mine(user_id: int) -> dict[str, object]:
    with unit_of_work(current_app) as db:
        actor = db.get(User, user_id)
        return {"open": False} if actor is None else class_wall.student_view(db, actor)


def student_channel(ws: WebSocket) -> Continuation | None:
    """The student's own seat: their hand, who holds their robot, the tutor's notices, whenever they change."""
    user_id = int(current_user.get_id())
    db = get_session()
    actor = db.get(User, user_id)
    found = class_sessions.my_seat(db, actor) if actor is not None else None
    if found is None:
        refuse(ws, CLOSE_NOT_FOUND, "no_class_session", gettext("No class session is open for your courses now."))
        return None
    class_session_id = found[1].session_id
    _listen(db)
    db.close()
    work = blocking_work()

    async def follow(live: LiveSocket) -> None:
        wake = _Wake(class_session_id, live)
        read_version, sent, read_at = -1, None, 0.0
        try:
            while live.connected:
                if wake.version() != read_version or time.monotonic() - read_at >= SEATS_EVERY_S:
                    read_version, read_at = wake.version(), time.monotonic()
                    mine = await work(_read_mine, user_id)
                    if mine != sent:
                        await live.send(as_json({"type": "seat", **mine}))
                        sent = mine
                    if not mine.get("open"):
                        break
                await live.receive(timeout=SEATS_EVERY_S)
        finally:
            wake.leave()

    return follow


def chat_room(class_session_id: int) -> str:
    """The class's chat room (middleware/chat): a name no robot has, so no robot's room is the class's."""
    return f"class:{class_session_id}"


def student_chat_channel(ws: WebSocket) -> Continuation | None:
    """The chat of the class the student has a seat in (the chat's own channel, in the class's room)."""
    db = get_session()
    actor = db.get(User, int(current_user.get_id()))
    found = class_sessions.my_seat(db, actor) if actor is not None else None
    db.close()
    if found is None:
        refuse(ws, CLOSE_NOT_FOUND, "no_class_session", gettext("No class session is open for your courses now."))
        return None
    return room_channel(ws, chat_room(found[1].session_id))


def tutor_chat_channel(ws: WebSocket, course_id: int) -> Continuation | None:
    """The chat of the course's open class, for its tutors and admins."""
    db = get_session()
    actor = db.get(User, int(current_user.get_id()))
    try:
        if actor is None:
            raise Refused(403, "forbidden", gettext("Log in again."))
        room = chat_room(class_wall.wall_session(db, actor, course_id)[1].id)
    except Refused as refused:
        _refusal_close(ws, refused)
        return None
    finally:
        db.close()
    return room_channel(ws, room)


def register(sock: Channels) -> None:
    """Declares the wall's channels and the class's chat."""
    sock.route("/ws/courses/<int:course_id>/class-wall", endpoint="class_wall_channel")(wall_channel)
    sock.route("/ws/class-session/wall", endpoint="class_student_wall_channel")(student_channel)
    sock.route("/ws/courses/<int:course_id>/class-wall/chat", endpoint="class_tutor_chat_channel")(tutor_chat_channel)
    sock.route("/ws/class-session/chat", endpoint="class_student_chat_channel")(student_chat_channel)
