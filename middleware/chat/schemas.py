"""Validation of chat input: bodies and the socket's commands."""

from __future__ import annotations

import re
import unicodedata
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.auth.schemas import InvalidField
from middleware.validation import parse_message

MAX_BODY_CHARS = 500
MAX_COMMAND_CHARS = 4096
MAX_ID = 2**53
LINE_KEY = re.compile(r"[A-Za-z0-9_-]{1,64}")


def clean_body(value: object) -> str:
    """The message text, trimmed: 1 to 500 characters, with no control characters."""
    if not isinstance(value, str):
        raise InvalidField("body", gettext("body must be text."))
    body = value.strip()
    if not body:
        raise InvalidField("body", gettext("Write something before sending."))
    if len(body) > MAX_BODY_CHARS:
        raise InvalidField("body", gettext("A message may have at most %(max_body_chars)s characters; this has "
                                           "%(count)s.", max_body_chars=MAX_BODY_CHARS, count=len(body)))
    # Cc: control characters (newlines included, a message is one line); Cs: lone surrogates no database stores.
    if any(unicodedata.category(char) in ("Cc", "Cs") for char in body):
        raise InvalidField("body", gettext("The message contains control characters; send plain text on one line."))
    return body


def clean_message_id(value: object, field: str = "id") -> int:
    """A message id: a positive whole number."""
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_ID:
        raise InvalidField(field, gettext("%(field)s must be a positive whole number.", field=field))
    return value


def clean_line_key(value: object) -> str | None:
    """The key the browser gave a line so it can match the answer to it (echoed, never stored): 1-64 letters,
    digits, '-' or '_'; None when absent."""
    if value is None:
        return None
    if not isinstance(value, str) or not LINE_KEY.fullmatch(value):
        raise InvalidField("line", gettext("line must be 1 to 64 letters, digits, '-' or '_'."))
    return value


@dataclass(frozen=True)
class ChatCommand:
    """A parsed socket message: say (body, checked by the service that stores it, and the line's key) or delete
    (message_id)."""

    kind: str
    body: object = ""
    message_id: int = 0
    line: str | None = None


def parse_chat_command(raw: object) -> ChatCommand:
    """A ChatCommand from one WebSocket text message, or a refusal (InvalidField, InvalidInput) naming the field."""
    message = parse_message(raw, ("say", "delete"), MAX_COMMAND_CHARS)
    if message["type"] == "say":
        return ChatCommand("say", body=message.get("body"), line=clean_line_key(message.get("line")))
    return ChatCommand("delete", message_id=clean_message_id(message.get("id")))
