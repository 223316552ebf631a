"""Channels of the skills: a goal's updates until it ends, and the localization estimate."""

from __future__ import annotations

import grpc
from flask import current_app
from flask_login import current_user

from middleware.lab.skills import GOAL_ID_PATTERN
from middleware.lab.sockets import CLOSE_UNKNOWN_ROBOT, _refuse, open_robot_channel, relay_stream, send_json, sock
from middleware.robots.messages import FINAL_GOAL_STATUSES, goal_update_message


def sees_ground_truth() -> bool:
    """Whether the current user's teaching mode shows the simulator's ground truth."""
    return current_user.role in current_app.config["GROUND_TRUTH_ROLES"]


@sock.route("/ws/robots/<robot_name>/goals/<goal_id>")
def goal_channel(ws, robot_name: str, goal_id: str) -> None:  # type: ignore[no-untyped-def]
    """Relays one goal's state, events and feedback; closes after its final state."""
    link = open_robot_channel(ws, robot_name)
    if link is None:
        return
    if not GOAL_ID_PATTERN.fullmatch(goal_id):
        _refuse(ws, CLOSE_UNKNOWN_ROBOT, "unknown_goal", "There is no goal with that id.", "goal_id")
        return
    updates = link.watch_goal(goal_id)
    try:
        for update in updates:
            if not ws.connected:
                break
            message = goal_update_message(update)
            send_json(ws, message)
            if message["type"] == "goal" and message["goal"]["status"] in FINAL_GOAL_STATUSES:
                break
    except grpc.RpcError as error:
        code = "unknown_goal" if error.code() == grpc.StatusCode.NOT_FOUND else "robot_offline"  # type: ignore[attr-defined]
        send_json(ws, {"type": "error", "code": code, "message": error.details() or "The robot is not answering.",  # type: ignore[attr-defined]
                       "field": "goal_id" if code == "unknown_goal" else None})
    finally:
        updates.cancel()


@sock.route("/ws/robots/<robot_name>/localization")
def localization_channel(ws, robot_name: str) -> None:  # type: ignore[no-untyped-def]
    """The localization estimate, particles and errors; the ground truth only where the teaching mode allows."""
    link = open_robot_channel(ws, robot_name)
    if link is not None:
        index = 0 if sees_ground_truth() else 1
        relay_stream(ws, link.localization, choose=lambda versions: versions[index])
