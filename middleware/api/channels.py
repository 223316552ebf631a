"""The WebSocket channels, described for the OpenAPI document's `x-websocket` section.

Each channel is a rule of the URL map (`realtime.Channels.route`); a page carries them all on one socket,
`/ws/link` (`live/link.py`), or opens one on its own. What a channel sends and takes is listed here by rule, with
the types its code checks (`validation.parse_message` refuses any other `type` with an error naming the field);
`undescribed_channels()` names a channel of the URL map missing here, and a test fails on it.
"""

from __future__ import annotations

from typing import Any

from flask import Flask

from middleware.api.contract import (
    BOOLEAN,
    ERROR,
    TIME,
    Schema,
    array,
    nullable,
    number,
    obj,
    obj_of,
    one_of,
    text,
    whole,
)

_ERROR_MESSAGE: Schema = obj(("type", "code", "message"), type=one_of("error"), code=text(), message=text(),
                             field={"type": ["string", "null"]})
_CLOSE_CODES = {"1008": "too many messages (a flood); handshakes refused for 10 s",
                "1009": "a message over 4096 bytes", "1011": "the channel failed (the link stays open)",
                "1012": "the worker is leaving: reconnect, the seat is kept",
                "1013": "try again later (a robot offline, a flood's cool-down)",
                "4401": "not logged in, or the login ended", "4403": "not allowed (another course's class)",
                "4404": "nothing there (an unknown robot, goal or class)"}

# The messages' shapes, as the code that builds each one writes them (middleware/robots/messages.py for the robot's
# streams, access/sockets.py's seat_message, chat/sockets.py, teaching/class_wall*.py, teaching/tour_live.py).
_POSE: Schema = obj(("x_m", "y_m", "theta_rad"), x_m=number(), y_m=number(), theta_rad=number())
_NUMBERS: Schema = array(number())
_TELEMETRY: Schema = obj(
    ("type", "tick", "sim_time_s", "capture_unix_s", "last_applied_sequence", "deadman_stopped", "battery",
     "odometry", "sonar", "laser", "line", "camera_pose"),
    type=one_of("telemetry"), tick=whole(0), sim_time_s=number(), capture_unix_s=number(),
    last_applied_sequence=whole(0), deadman_stopped=BOOLEAN,
    battery=obj(("charge", "charging", "empty"), charge=number(0, 1), charging=BOOLEAN, empty=BOOLEAN),
    odometry=obj(("pose", "linear_mps", "angular_radps"), pose=_POSE, linear_mps=number(), angular_radps=number()),
    sonar=obj(("ranges_m",), ranges_m=_NUMBERS),
    laser=obj(("angle_min_rad", "angle_increment_rad", "ranges_m"), angle_min_rad=number(),
              angle_increment_rad=number(), ranges_m=_NUMBERS),
    line=obj(("values",), values=_NUMBERS),
    camera_pose=nullable(_POSE) | {"description": "where the robot truly stands (for a drawn camera); null in a "
                                                  "graded run"})
_FEEDBACK: Schema = obj(
    ("sim_time_s", "state", "progress", "distance_error_m", "heading_error_rad", "pose", "pose_source", "values",
     "planned_path"),
    sim_time_s=number(), state=text(), progress=number(), distance_error_m=number(), heading_error_rad=number(),
    pose=_POSE, pose_source=text(), values={"type": "object", "additionalProperties": number()},
    planned_path=array(array(number(), minItems=2, maxItems=2, description="[x_m, y_m]"), 64))
_GOAL_MESSAGES: list[Schema] = [
    obj(("type", "goal"), type=one_of("goal"), goal=obj(
        ("goal_id", "skill", "motor", "status", "parameters", "error_code", "message", "goal_reached", "feedback"),
        goal_id=text(), skill=text(), motor=BOOLEAN,
        status=one_of("unspecified", "accepted", "executing", "canceling", "succeeded", "canceled", "aborted"),
        parameters={"type": "object", "additionalProperties": {"type": ["number", "boolean", "string", "null"]}},
        error_code=text(), message=text(), goal_reached=BOOLEAN, feedback=nullable(_FEEDBACK))),
    obj(("type", "kind", "message", "sim_time_s"), type=one_of("goal_event"), kind=text(), message=text(),
        sim_time_s=number()),
    obj(("type", "feedback"), type=one_of("goal_feedback"), feedback=_FEEDBACK),
]
_NULLABLE_NUMBER: Schema = nullable(number())
_LOCALIZATION: Schema = obj(
    ("type", "sim_time_s", "active", "converged", "estimate", "std_x_m", "std_y_m", "std_theta_rad", "odometry",
     "navigation", "update_duration_ms", "particles", "ground_truth", "position_error_m", "heading_error_rad",
     "odometry_position_error_m", "odometry_heading_error_rad"),
    type=one_of("localization"), sim_time_s=number(), active=BOOLEAN, converged=BOOLEAN, estimate=_POSE,
    std_x_m=number(), std_y_m=number(), std_theta_rad=number(), odometry=_POSE,
    navigation=nullable(obj(("pose", "source"), pose=_POSE, source=text())), update_duration_ms=number(),
    particles=array(array(number(), minItems=4, maxItems=4, description="[x_m, y_m, theta_rad, weight]")),
    ground_truth=nullable(_POSE) | {"description": "null where the teaching mode hides it, and in a graded run"},
    position_error_m=_NULLABLE_NUMBER, heading_error_rad=_NULLABLE_NUMBER,
    odometry_position_error_m=_NULLABLE_NUMBER, odometry_heading_error_rad=_NULLABLE_NUMBER)
_QUEUE: Schema = obj(
    ("type", "in_queue", "is_controller", "position", "queue_size", "pool_waiting", "turn_remaining_s",
     "estimated_wait_s", "warning", "faulted", "controller"),
    type=one_of("queue"), in_queue=BOOLEAN, is_controller=BOOLEAN,
    position=whole(-1, description="0 for the controller, 1.. waiting, -1 not in the queue"), queue_size=whole(0),
    pool_waiting=whole(0), turn_remaining_s=_NULLABLE_NUMBER, estimated_wait_s=_NULLABLE_NUMBER, warning=BOOLEAN,
    faulted=BOOLEAN, controller=nullable(text(description="the controller's username")))
_CHAT_LINE: Schema = obj(("id", "robot_name", "body", "author", "author_role", "created_at"), id=whole(1),
                         robot_name=text(), body=text(), author=text(), author_role=text(), created_at=TIME)
_CHAT_MESSAGES: list[Schema] = [
    obj(("type", "robot_name", "can_moderate", "user", "messages"), type=one_of("history"), robot_name=text(),
        can_moderate=BOOLEAN, user=text(), messages=array(_CHAT_LINE)),
    obj(("type", "message"), type=one_of("message"), message=_CHAT_LINE),
    obj(("type", "id"), type=one_of("deleted"), id=whole(1)),
    obj(("type", "id", "line"), type=one_of("sent"), id=whole(1), line=nullable(text(64))),
    obj(("type", "code", "message"), type=one_of("error"), code=text(), message=text(), field=nullable(text()),
        line=nullable(text(64, description="the key of the line refused"))),
]
# A stream relayed from the robot (camera, telemetry, localization) says when the robot goes off or on line, and
# when the viewer's injected delay changes (realtime.relay_stream, experiment/delay.apply_viewer_delay).
_STATUS: Schema = obj(("type", "robot_online", "message"), type=one_of("status"), robot_online=BOOLEAN,
                      message=text(), injected_delay_s=number(0))
_CHAT_RECEIVES: list[Schema] = [
    obj(("type", "body"), type=one_of("say"), body=text(500),
        line=text(64, description="the sender's key for the line, echoed in its answer")),
    obj(("type", "id"), type=one_of("delete"), id=whole(1, 2**53)),
]
_HAND: Schema = nullable(obj(("text", "raised_at"), text=text(), raised_at=TIME))
_WALL_SEAT: Schema = obj(("user_id", "username", "robot", "seat_state", "message", "hand", "held_by", "testing"),
                         user_id=whole(1), username=text(), robot=text(), seat_state=text(), message=text(),
                         hand=_HAND, held_by=nullable(text()), testing=BOOLEAN)
_POSE_ROW: Schema = array(minItems=8, maxItems=8, description="[user id, x_m, y_m, theta_rad, linear_mps, "
                          "angular_radps, battery charge or null, activity]",
                          prefixItems=[whole(1), number(), number(), number(), number(), number(),
                                       nullable(number()), text()])
_STUDENT_SEAT: Schema = obj(
    ("type", "open"), type=one_of("seat"), open=BOOLEAN, session_id=whole(1), course_id=whole(1), robot=text(),
    hand=_HAND, held_by=nullable(text()),
    notices=array(obj_of(("id", "kind", "from", "at"),
                         {"id": whole(1), "kind": text(), "from": nullable(text()), "at": TIME},
                         description="each notice also carries its kind's own fields")),
    description="open false (and nothing else) once the class ended")
_TOUR_STATE: Schema = obj(
    ("type", "id", "tour_id", "robot", "tutor", "step_index", "step_count", "step", "controller", "ended",
     "version", "participants"),
    type=one_of("state"), id=whole(1), tour_id=whole(1), robot=text(), tutor=nullable(text()), step_index=whole(),
    step_count=whole(0), step=nullable(obj(("title", "text", "panel", "command", "condition"), title=text(),
                                           text=text(), panel=text(), command={"type": ["object", "null"]},
                                           condition=obj(("type",), type=text(), seconds=number()))),
    controller=nullable(text()), ended=BOOLEAN, version=whole(), participants=array(text()))

CHANNELS: dict[str, dict[str, Any]] = {
    "/ws/link": {
        "summary": "Every channel of a page on one socket: subscribe by path; a channel's messages carry its number "
                   "('7 {...}', or 4 bytes big-endian before a binary one). Control messages travel on sub 0.",
        "receives": [obj(("type", "sub", "path"), type=one_of("subscribe"), sub=whole(1, 2**31 - 1),
                         path=text(512, description="a channel's path, e.g. /ws/robots/lab-1/camera")),
                     obj(("type", "sub"), type=one_of("unsubscribe"), sub=whole(1, 2**31 - 1)),
                     {"type": "string", "description": "'<sub> <text>': a message to channel <sub>"}],
        "sends": [obj(("type", "max_channels"), type=one_of("ready"), max_channels=whole(1, 24)),
                  obj(("type", "sub"), type=one_of("subscribed"), sub=whole(1)),
                  obj(("type", "sub", "code"), type=one_of("closed"), sub=whole(1), code=whole(1000, 4999),
                      reason=text()),
                  _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/camera": {
        "summary": "The robot's camera: binary JPEG frames, each after a JSON header with its capture time and "
                   "the sequence number of the last command applied.",
        "receives": [], "sends": [{"type": "string", "format": "binary"}, _STATUS, _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/telemetry": {
        "summary": "The robot's pose, odometry, sonar and laser as JSON, latest message wins for a slow viewer.",
        "receives": [], "sends": [_TELEMETRY, _STATUS, _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/drive": {
        "summary": "Drive the robot while holding its turn (50 messages a second at most); each command is acked.",
        "receives": [obj(("type", "sequence", "linear_mps", "angular_radps"), type=one_of("drive"),
                         sequence=whole(1, 2**53), linear_mps=number(), angular_radps=number()),
                     obj(("type", "sequence"), type=one_of("stop"), sequence=whole(1, 2**53)),
                     obj(("type", "id"), type=one_of("ping"), id=whole(0))],
        "sends": [obj(("type",), type=one_of("ready"), max_linear_mps=number(), max_angular_radps=number(),
                      send_interval_ms=whole(1), sequence_base=whole(0), is_controller={"type": "boolean"}),
                  obj(("type", "sequence"), type=one_of("ack"), sequence=whole(1), applied_sequence=whole(0),
                      linear_mps=number(), angular_radps=number(), robot_rtt_ms=number(),
                      superseded=whole(0, description="older commands this one replaced while the robot was busy")),
                  obj(("type",), type=one_of("pong")), _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/goals/<goal_id>": {
        "summary": "One skill goal's state, events and feedback; closes after its final state.",
        "receives": [], "sends": [*_GOAL_MESSAGES, _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/localization": {
        "summary": "The robot's localization estimate (hidden during a graded run).",
        "receives": [], "sends": [_LOCALIZATION, _STATUS, _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/queue": {
        "summary": "The robot's queue and the user's seat: join, pass the turn, leave; a seat message when it "
                   "changes and every 10 s.",
        "receives": [obj(("type",), type=one_of("join", "pass", "leave"))],
        "sends": [_QUEUE, _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/chat": {
        "summary": "The robot's chat room: history, new lines, deletions by a moderator.",
        "receives": _CHAT_RECEIVES,
        "sends": _CHAT_MESSAGES,
    },
    "/ws/practice/camera": {
        "summary": "The camera of the user's practice robot, as the lab camera's channel.",
        "receives": [], "sends": [{"type": "string", "format": "binary"}, _STATUS, _ERROR_MESSAGE],
    },
    "/ws/courses/<int:course_id>/class-wall": {
        "summary": "The class wall for the course's tutors: every seat when one changes, every robot's pose, and "
                   "'ended' when the class session ends.",
        "receives": [],
        "sends": [obj(("type", "seats"), type=one_of("seats"), seats=array(_WALL_SEAT)),
                  obj(("type", "t", "robots"), type=one_of("poses"), t=number(), robots=array(_POSE_ROW)),
                  obj(("type",), type=one_of("ended")),
                  _ERROR_MESSAGE],
    },
    "/ws/class-session/wall": {
        "summary": "The student's own seat in the open class: their hand, who holds their robot, the tutor's notices.",
        "receives": [], "sends": [_STUDENT_SEAT, _ERROR_MESSAGE],
    },
    "/ws/courses/<int:course_id>/class-wall/chat": {
        "summary": "The chat of the course's open class, for its tutors and admins (the chat channel's messages).",
        "receives": _CHAT_RECEIVES,
        "sends": _CHAT_MESSAGES,
    },
    "/ws/class-session/chat": {
        "summary": "The chat of the class the student has a seat in (the chat channel's messages).",
        "receives": _CHAT_RECEIVES,
        "sends": _CHAT_MESSAGES,
    },
    "/ws/tour-sessions/<int:session_id>": {
        "summary": "A live class's state for its followers: the step, the robot, who has control.",
        "receives": [], "sends": [_TOUR_STATE, _ERROR_MESSAGE],
    },
}


def channel_rules(app: Flask) -> list[str]:
    """The WebSocket rules of app's URL map."""
    return sorted(rule.rule for rule in app.url_map.iter_rules() if rule.websocket)


def undescribed_channels(app: Flask) -> list[str]:
    """The channels of app's URL map this module does not describe."""
    return [rule for rule in channel_rules(app) if rule not in CHANNELS]


def describe(app: Flask) -> dict[str, Any]:
    """The x-websocket section: the link, each channel's messages both ways, the close codes."""
    return {
        "link": "/ws/link",
        "closeCodes": _CLOSE_CODES,
        "error": ERROR,
        "channels": {rule: CHANNELS[rule] for rule in channel_rules(app) if rule in CHANNELS},
    }
