"""Invitations by link: the way into the lab (self-registration is off). No Flask request state in here.

A tutor invites students into a course they teach; an admin invites any role, into a course or none.
The token is random and only its SHA-256 hash is stored; a link expires and works once (the database
marks it accepted with a conditional UPDATE, so two people racing on one link cannot both join).
"""

from __future__ import annotations

import hashlib
import secrets
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select, update
from sqlalchemy.orm import Session

from middleware.accounts.services import forbidden, is_course_tutor
from middleware.auth.schemas import InvalidField, clean_new_password, clean_role, clean_username
from middleware.auth.services import AccountExists, create_user
from middleware.errors import Refused
from middleware.locking import rows_matched
from middleware.models import Course, CourseMembership, Invitation, Role, User


def token_hash(token: str) -> str:
    """The SHA-256 hex digest stored in place of the token."""
    return hashlib.sha256(token.encode()).hexdigest()


def _as_utc(moment: datetime) -> datetime:
    return moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)


@dataclass(frozen=True)
class InvitationView:
    """An invitation as lists show it (never the token)."""

    id: int
    role: str
    course_code: str | None
    created_at: datetime
    expires_at: datetime
    status: str  # pending | accepted | expired | revoked

    def to_dict(self) -> dict[str, object]:
        """The JSON form."""
        return {"id": self.id, "role": self.role, "course_code": self.course_code, "status": self.status,
                "created_at": self.created_at.isoformat(), "expires_at": self.expires_at.isoformat()}


def create_invitation(session: Session, actor: User, role: object, course_id: int | None,
                      lasts: timedelta, now: datetime) -> tuple[Invitation, str]:
    """A new invitation and its token (shown once, as part of the link). The caller commits."""
    invited_role = clean_role(role)
    course = session.get(Course, course_id) if course_id is not None else None
    if course_id is not None and course is None:
        raise Refused(404, "unknown_course", gettext("There is no course with id %(course_id)s.", course_id=course_id),
                                             "course_id")
    if actor.role == Role.TUTOR:
        if course is None or not is_course_tutor(session, actor.id, course.id):
            raise forbidden(gettext("You can invite people only into a course you teach."))
        if invited_role != Role.STUDENT:
            raise Refused(403, "forbidden", gettext("Tutors invite students; ask an admin to invite a tutor."), "role")
    elif actor.role != Role.ADMIN:
        raise forbidden(gettext("Only tutors and admins can invite people."))
    if course is not None and invited_role == Role.ADMIN:
        raise Refused(400, "invalid_field", gettext("An admin is not invited into a course; leave the course empty."),
                      "course_id")
    token = secrets.token_urlsafe(32)
    invitation = Invitation(token_hash=token_hash(token), role=invited_role.value,
                            course_id=course.id if course else None, created_by_id=actor.id,
                            created_at=now, expires_at=now + lasts)
    session.add(invitation)
    session.flush()
    return invitation, token


def _status(invitation: Invitation, now: datetime) -> str:
    if invitation.accepted_at is not None:
        return "accepted"
    if invitation.revoked_at is not None:
        return "revoked"
    return "expired" if _as_utc(invitation.expires_at) <= now else "pending"


def _view(invitation: Invitation, course_code: str | None, now: datetime) -> InvitationView:
    return InvitationView(invitation.id, invitation.role, course_code, _as_utc(invitation.created_at),
                          _as_utc(invitation.expires_at), _status(invitation, now))


def revoke_invitation(session: Session, actor: User, invitation_id: int, now: datetime) -> InvitationView:
    """Withdraws a pending invitation (its course's tutors, admins); its link stops working. The caller commits."""
    invitation = session.get(Invitation, invitation_id)
    if invitation is None:
        raise Refused(404, "unknown_invitation", gettext("There is no such invitation."), "invitation_id")
    if actor.role != Role.ADMIN and (invitation.course_id is None
                                     or not is_course_tutor(session, actor.id, invitation.course_id)):
        raise forbidden(gettext("You can withdraw invitations only of courses you teach."))
    status = _status(invitation, now)
    if status != "pending":
        raise Refused(409, "invitation_not_pending", gettext("This invitation is %(status)s; only a pending one can "
                                                             "be withdrawn.", status=status), "invitation_id")
    # Conditional, so a link being accepted at this moment is either used or withdrawn, never both.
    withdrawn = rows_matched(session, update(Invitation).where(
        Invitation.id == invitation.id, Invitation.accepted_at.is_(None), Invitation.revoked_at.is_(None))
        .values(revoked_at=now))
    if withdrawn != 1:
        raise Refused(409, "invitation_not_pending", gettext("This invitation was used a moment ago."), "invitation_id")
    session.refresh(invitation)
    course = session.get(Course, invitation.course_id) if invitation.course_id is not None else None
    return _view(invitation, course.code if course else None, now)


def list_invitations(session: Session, actor: User, course_id: int | None, now: datetime) -> list[InvitationView]:
    """Invitations of a course (its tutors, admins) or, with no course, every invitation (admins)."""
    query = select(Invitation, Course.code).outerjoin(Course, Course.id == Invitation.course_id)
    if course_id is None:
        if actor.role != Role.ADMIN:
            raise forbidden(gettext("Only an admin can list every invitation."))
    else:
        if actor.role != Role.ADMIN and not is_course_tutor(session, actor.id, course_id):
            raise forbidden(gettext("You can see the invitations only of courses you teach."))
        query = query.where(Invitation.course_id == course_id)
    rows = session.execute(query.order_by(Invitation.created_at.desc(), Invitation.id.desc()).limit(200))
    return [_view(invitation, code, now) for invitation, code in rows]


class InvitationUnusable(Exception):
    """The link cannot be used: reason is 'unknown', 'expired', 'used' or 'revoked'."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def find_usable(session: Session, token: str, now: datetime) -> tuple[Invitation, Course | None]:
    """The pending invitation behind token and its course, or InvitationUnusable saying why not."""
    if not isinstance(token, str) or not 20 <= len(token) <= 100:
        raise InvitationUnusable("unknown")
    invitation = session.scalar(select(Invitation).where(Invitation.token_hash == token_hash(token)))
    if invitation is None:
        raise InvitationUnusable("unknown")
    status = _status(invitation, now)
    if status != "pending":
        raise InvitationUnusable({"accepted": "used", "revoked": "revoked"}.get(status, "expired"))
    course = session.get(Course, invitation.course_id) if invitation.course_id is not None else None
    return invitation, course


def accept(session: Session, token: str, username: object, password: object, password_again: object,
           now: datetime) -> User:
    """Creates the invited account, enrols it in the invitation's course and uses the link up. The caller commits."""
    invitation, course = find_usable(session, token, now)
    name = clean_username(username)
    clean_password = clean_new_password(password)
    if password_again != clean_password:
        raise InvalidField("password_again", gettext("The two passwords differ; type the same password twice."))
    used = rows_matched(session, update(Invitation).where(
        Invitation.id == invitation.id, Invitation.accepted_at.is_(None), Invitation.revoked_at.is_(None))
        .values(accepted_at=now))
    if used != 1:
        raise InvitationUnusable("used")
    try:
        user = create_user(session, name, invitation.role, clean_password)
    except AccountExists:
        raise Refused(409, "account_exists", gettext("The username %(name)s is taken; choose another.",
                                                     name=repr(name)),
                                             "username") from None
    session.execute(update(Invitation).where(Invitation.id == invitation.id).values(accepted_user_id=user.id))
    if course is not None and invitation.role in (Role.STUDENT, Role.TUTOR):
        session.add(CourseMembership(course_id=course.id, user_id=user.id, role=invitation.role))
        session.flush()
    return user
