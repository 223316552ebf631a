"""The WebSocket channels, described for the OpenAPI document's `x-websocket` section.

Each channel is a rule of the URL map (`realtime.Channels.route`); a page carries them all on one socket,
`/ws/link` (`live/link.py`), or opens one on its own. What a channel sends and takes is listed here by rule, with
the types its code checks (`validation.parse_message` refuses any other `type` with an error naming the field);
`undescribed_channels()` names a channel of the URL map missing here, and a test fails on it.
"""

from __future__ import annotations

from typing import Any

from flask import Flask

from middleware.api.contract import ERROR, Schema, array, number, obj, one_of, text, whole

_ERROR_MESSAGE: Schema = obj(("type", "code", "message"), type=one_of("error"), code=text(), message=text(),
                             field={"type": ["string", "null"]})
_CLOSE_CODES = {"1008": "too many messages (a flood); handshakes refused for 10 s",
                "1009": "a message over 4096 bytes", "1011": "the channel failed (the link stays open)",
                "1012": "the worker is leaving: reconnect, the seat is kept",
                "1013": "try again later (a robot offline, a flood's cool-down)",
                "4401": "not logged in, or the login ended", "4403": "not allowed (another course's class)",
                "4404": "nothing there (an unknown robot, goal or class)"}

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
        "receives": [], "sends": [{"type": "string", "format": "binary"}, _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/telemetry": {
        "summary": "The robot's pose, odometry, sonar and laser as JSON, latest message wins for a slow viewer.",
        "receives": [], "sends": [obj(("type",), type=one_of("telemetry")), _ERROR_MESSAGE],
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
                      linear_mps=number(), angular_radps=number(), robot_rtt_ms=number()),
                  obj(("type",), type=one_of("pong")), _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/goals/<goal_id>": {
        "summary": "One skill goal's state, events and feedback; closes after its final state.",
        "receives": [], "sends": [obj(("type",), type=one_of("goal", "feedback", "event")), _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/localization": {
        "summary": "The robot's localization estimate (hidden during a graded run).",
        "receives": [], "sends": [obj(("type",)), _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/queue": {
        "summary": "The robot's queue and the user's seat: join, pass the turn, leave; a seat message when it "
                   "changes and every 10 s.",
        "receives": [obj(("type",), type=one_of("join", "pass", "leave"))],
        "sends": [obj(("type",), type=one_of("queue")), _ERROR_MESSAGE],
    },
    "/ws/robots/<robot_name>/chat": {
        "summary": "The robot's chat room: history, new lines, deletions by a moderator.",
        "receives": [obj(("type",), type=one_of("say", "delete"), text=text(500), id=whole(1),
                         line=text(64, description="the sender's key for the line, echoed in its answer"))],
        "sends": [obj(("type",), type=one_of("history", "message", "deleted", "sent")), _ERROR_MESSAGE],
    },
    "/ws/practice/camera": {
        "summary": "The camera of the user's practice robot, as the lab camera's channel.",
        "receives": [], "sends": [{"type": "string", "format": "binary"}, _ERROR_MESSAGE],
    },
    "/ws/courses/<int:course_id>/class-wall": {
        "summary": "The class wall for the course's tutors: every seat when one changes, every robot's pose, and "
                   "'ended' when the class session ends.",
        "receives": [],
        "sends": [obj(("type", "seats"), type=one_of("seats"), seats=array()),
                  obj(("type",), type=one_of("poses"), t=number()), obj(("type",), type=one_of("ended")),
                  _ERROR_MESSAGE],
    },
    "/ws/class-session/wall": {
        "summary": "The student's own seat in the open class: their hand, who holds their robot, the tutor's notices.",
        "receives": [], "sends": [obj(("type",), type=one_of("seat")), _ERROR_MESSAGE],
    },
    "/ws/courses/<int:course_id>/class-wall/chat": {
        "summary": "The chat of the course's open class, for its tutors and admins (the chat channel's messages).",
        "receives": [obj(("type",), type=one_of("say", "delete"), text=text(500), id=whole(1), line=text(64))],
        "sends": [obj(("type",), type=one_of("history", "message", "deleted", "sent")), _ERROR_MESSAGE],
    },
    "/ws/class-session/chat": {
        "summary": "The chat of the class the student has a seat in (the chat channel's messages).",
        "receives": [obj(("type",), type=one_of("say", "delete"), text=text(500), id=whole(1), line=text(64))],
        "sends": [obj(("type",), type=one_of("history", "message", "deleted", "sent")), _ERROR_MESSAGE],
    },
    "/ws/tour-sessions/<int:session_id>": {
        "summary": "A live class's state for its followers: the step, the robot, who has control.",
        "receives": [], "sends": [obj(("type",), type=one_of("state")), _ERROR_MESSAGE],
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
