"""The queue channel: each connected user's seat, live, and the pass/leave/join actions."""

from __future__ import annotations

import json
import time

from flask import Flask
from flask_login import current_user
from sqlalchemy import select

from middleware.access import round_robin
from middleware.access.coordinator import AccessCoordinator, access_coordinator
from middleware.db import session_factory
from middleware.lab.sockets import open_robot_channel, send_json, sock
from middleware.models import User

HEARTBEAT_INTERVAL_S = 2.0
REFRESH_INTERVAL_S = 0.5
ACTIONS = {"pass": round_robin.pass_turn, "leave": round_robin.leave}


def seat_message(coordinator: AccessCoordinator, robot_name: str, user_id: int) -> dict[str, object]:
    """The queue as user_id sees it, as a JSON-ready message."""
    state = coordinator.snapshot(robot_name)
    turn_length_s = coordinator.turn_length_s(state.controller_id or user_id)
    seat = round_robin.seat_of(state, user_id, coordinator.now(), turn_length_s)
    controller_name = None
    if state.controller_id is not None:
        with session_factory(coordinator.app)() as session:
            controller_name = session.scalar(select(User.username).where(User.id == state.controller_id))
    return {
        "type": "queue",
        "in_queue": seat.in_queue,
        "is_controller": seat.is_controller,
        "position": seat.position,
        "queue_size": seat.queue_size,
        "turn_remaining_s": None if seat.turn_remaining_s is None else round(seat.turn_remaining_s, 1),
        "estimated_wait_s": None if seat.estimated_wait_s is None else round(seat.estimated_wait_s, 1),
        "warning": seat.warning,
        "faulted": seat.faulted,
        "controller": controller_name,
    }


def parse_queue_action(raw: object) -> str:
    """The action named by a queue message, or ValueError with a sentence."""
    try:
        message = json.loads(raw) if isinstance(raw, str) and len(raw) <= 256 else None
    except ValueError:
        message = None
    action = message.get("type") if isinstance(message, dict) else None
    if action not in {"pass", "leave", "join"}:
        raise ValueError("type must be 'pass', 'leave' or 'join'.")
    return action


@sock.route("/ws/robots/<robot_name>/queue")
def queue_channel(ws, robot_name: str) -> None:  # type: ignore[no-untyped-def]
    """Joins the robot's queue and reports the user's seat until the socket closes (the seat outlives it)."""
    if open_robot_channel(ws, robot_name) is None:
        return
    coordinator = access_coordinator()
    coordinator.start_ticker()
    user_id = int(current_user.get_id())
    coordinator.join(robot_name, user_id)
    last_sent: dict[str, object] | None = None
    last_sent_at = last_heartbeat = 0.0
    while ws.connected:
        raw = ws.receive(timeout=REFRESH_INTERVAL_S)
        if raw is not None:
            try:
                action = parse_queue_action(raw)
            except ValueError as invalid:
                send_json(ws, {"type": "error", "code": "invalid_field", "message": str(invalid), "field": "type"})
                continue
            if action == "join":
                coordinator.join(robot_name, user_id)
            else:
                coordinator.apply(ACTIONS[action], robot_name, user_id)
            last_sent = None
        now = time.monotonic()
        if now - last_heartbeat >= HEARTBEAT_INTERVAL_S:
            coordinator.heartbeat(robot_name, user_id)
            last_heartbeat = now
        message = seat_message(coordinator, robot_name, user_id)
        if message != last_sent or now - last_sent_at >= 1.0:
            send_json(ws, message)
            last_sent, last_sent_at = message, now


def init_app(app: Flask) -> None:
    """Creates the coordinator for app (the channel itself is registered with the shared `sock`)."""
    from middleware.access.coordinator import init_app as init_coordinator

    init_coordinator(app)
