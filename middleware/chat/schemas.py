"""Validation of chat input: bodies and the socket's commands."""

from __future__ import annotations

import unicodedata
from dataclasses import dataclass

from middleware.auth.schemas import InvalidField
from middleware.validation import parse_message

MAX_BODY_CHARS = 500
MAX_COMMAND_CHARS = 4096
MAX_ID = 2**53


def clean_body(value: object) -> str:
    """The message text, trimmed: 1 to 500 characters, with no control characters."""
    if not isinstance(value, str):
        raise InvalidField("body", "body must be text.")
    body = value.strip()
    if not body:
        raise InvalidField("body", "Write something before sending.")
    if len(body) > MAX_BODY_CHARS:
        raise InvalidField("body", f"A message may have at most {MAX_BODY_CHARS} characters; this has {len(body)}.")
    # Cc: control characters (newlines included, a message is one line); Cs: lone surrogates no database stores.
    if any(unicodedata.category(char) in ("Cc", "Cs") for char in body):
        raise InvalidField("body", "The message contains control characters; send plain text on one line.")
    return body


def clean_message_id(value: object, field: str = "id") -> int:
    """A message id: a positive whole number."""
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_ID:
        raise InvalidField(field, f"{field} must be a positive whole number.")
    return value


@dataclass(frozen=True)
class ChatCommand:
    """A parsed socket message: say (body) or delete (message_id)."""

    kind: str
    body: str = ""
    message_id: int = 0


def parse_chat_command(raw: object) -> ChatCommand:
    """A ChatCommand from one WebSocket text message, or a refusal (InvalidField, InvalidInput) naming the field."""
    message = parse_message(raw, ("say", "delete"), MAX_COMMAND_CHARS)
    if message["type"] == "say":
        return ChatCommand("say", body=clean_body(message.get("body")))
    return ChatCommand("delete", message_id=clean_message_id(message.get("id")))
