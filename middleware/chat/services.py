"""Chat rules: posting under a rate limit counted in the database, reading, and moderation. No request state."""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from middleware import events
from middleware.chat.schemas import clean_body
from middleware.errors import Refused
from middleware.locking import lock_chat_room, lock_user
from middleware.models import ChatMessage, User

RATE_LIMIT_MESSAGES = 5
RATE_LIMIT_WINDOW = timedelta(seconds=10)
HISTORY_LENGTH = 50
MODERATOR_ROLES = ("tutor", "admin")


class ChatRefused(Refused):
    """A chat action refused (status, stable code, sentence, field: see middleware.errors.Refused)."""


def public_name(username: str, user_id: int) -> str:
    """How a student sees another person in chat: initials and the account number ('ada.lovelace' -> 'A.L. #7'),
    so the room does not hand out login names to guess passwords for."""
    initials = "".join(f"{part[0].upper()}." for part in re.split(r"[._-]+", username) if part)
    return f"{initials} #{user_id}"


@dataclass(frozen=True)
class MessageView:
    """A message; the body is plain text for the client to escape. to_dict words the author for one viewer."""

    id: int
    robot_name: str
    body: str
    author_id: int
    author_username: str
    author_role: str
    created_at: datetime

    def to_dict(self, viewer_id: int, viewer_may_moderate: bool) -> dict[str, object]:
        """The JSON form for a viewer: tutors and admins (and the author) see the username, others public_name."""
        stamp = self.created_at.replace(tzinfo=UTC) if self.created_at.tzinfo is None else self.created_at
        named = viewer_may_moderate or viewer_id == self.author_id
        author = self.author_username if named else public_name(self.author_username, self.author_id)
        return {"id": self.id, "robot_name": self.robot_name, "body": self.body, "author": author,
                "author_role": self.author_role, "created_at": stamp.astimezone(UTC).isoformat().replace("+00:00", "Z")}


def _views(session: Session, query) -> list[MessageView]:
    rows = session.execute(query.join(User, User.id == ChatMessage.user_id)
                           .add_columns(User.username, User.role)).all()
    return [MessageView(m.id, m.robot_name, m.body, m.user_id, name, role, m.created_at) for m, name, role in rows]


def post_message(session: Session, robot_name: str, user: User, body: object, now: datetime) -> MessageView:
    """Stores a message after validation and the rate limit (5 per 10 s per user, all robots); caller commits."""
    text = clean_body(body)
    lock_user(session, user.id)  # two processes cannot both see "4 so far" and both insert
    recent = session.execute(select(func.count()).select_from(ChatMessage).where(
        ChatMessage.user_id == user.id, ChatMessage.created_at > now - RATE_LIMIT_WINDOW)).scalar_one()
    if recent >= RATE_LIMIT_MESSAGES:
        raise ChatRefused(429, "rate_limited", gettext("You can send %(rate_limit_messages)s messages every "
                                                       "%(seconds)s seconds; wait a moment and send it again.",
                                                       rate_limit_messages=RATE_LIMIT_MESSAGES,
                                                       seconds=RATE_LIMIT_WINDOW.seconds), "body")
    message = ChatMessage(robot_name=robot_name, user_id=user.id, body=text, created_at=now)
    lock_chat_room(session, robot_name)  # ids in commit order: the live cursor never passes one still in flight
    session.add(message)
    session.flush()
    events.announce(session, "chat", robot_name)
    return MessageView(message.id, robot_name, text, user.id, user.username, user.role, now)


def recent_messages(
    session: Session, robot_name: str, after_id: int = 0, limit: int = HISTORY_LENGTH
) -> list[MessageView]:
    """Visible messages oldest first: the last `limit` ones, or those after after_id (at most `limit`)."""
    query = select(ChatMessage).where(ChatMessage.robot_name == robot_name, ChatMessage.deleted_at.is_(None))
    if after_id:
        return _views(session, query.where(ChatMessage.id > after_id).order_by(ChatMessage.id).limit(limit))
    return list(reversed(_views(session, query.order_by(ChatMessage.id.desc()).limit(limit))))


def latest_id(session: Session, robot_name: str) -> int:
    """The newest message id of the room (deleted ones included), 0 when empty."""
    return session.scalar(select(func.max(ChatMessage.id)).where(ChatMessage.robot_name == robot_name)) or 0


def deleted_ids(session: Session, robot_name: str, from_id: int) -> list[int]:
    """Ids from from_id on that have been deleted."""
    return list(session.scalars(select(ChatMessage.id).where(
        ChatMessage.robot_name == robot_name, ChatMessage.id >= from_id, ChatMessage.deleted_at.is_not(None))))


def may_moderate(user: User) -> bool:
    """Tutors and admins may delete messages."""
    return user.role in MODERATOR_ROLES


def delete_message(session: Session, robot_name: str, actor: User, message_id: int, now: datetime) -> None:
    """Soft-deletes a message of this room (tutors and admins only); the caller commits."""
    if not may_moderate(actor):
        raise ChatRefused(403, "forbidden", gettext("Only tutors and admins can delete messages."), "id")
    message = session.get(ChatMessage, message_id)
    if message is None or message.robot_name != robot_name or message.deleted_at is not None:
        raise ChatRefused(404, "unknown_message", gettext("There is no message %(message_id)s in this chat.",
                                                          message_id=message_id), "id")
    message.deleted_at = now
    message.deleted_by_id = actor.id
    events.announce(session, "chat", robot_name)
