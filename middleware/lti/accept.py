"""A checked launch accepted: the person, the course, the enrolments and the placed target, in the request's unit
of work (a refusal anywhere discards all of it)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.lti import launches
from middleware.lti.flow import ValidatedLaunch
from middleware.lti.launches import LaunchRefused, Target
from middleware.models import Role, User
from middleware.models.assessment import Exam
from middleware.models.lti import LtiIdentity


@dataclass(frozen=True)
class AcceptedLaunch:
    """Who launched, into which Telelab course, to open what."""

    user: User
    course_id: int | None
    target: Target | None
    teaches: bool


def accept_launch(session: Session, validated: ValidatedLaunch, secret: str) -> AcceptedLaunch:
    """Matches or makes the person and the course, enrols, and reads the placed target."""
    claims = validated.claims
    teaches = launches.is_teacher(claims.get(launches.ROLES_CLAIM))
    if validated.is_deep_link and not teaches:
        raise LaunchRefused("not_instructor", "Only the LMS course's instructors place Telelab content.", 403)
    user = launches.match_user(session, validated.platform.issuer, claims, teaches)
    context = launches.map_context(session, validated.platform, claims)
    if context is not None:
        launches.enrol(session, context.course_id, user, teaches)
    target = None if validated.is_deep_link else launches.read_target(claims, secret)
    if target is not None and target.kind == "exam":
        exam = session.get(Exam, int(target.key)) if target.key.isdigit() else None
        if exam is None:
            raise LaunchRefused("unknown_target", "This test no longer exists in Telelab. Ask your tutor.", 404)
        if not teaches and user.role == Role.STUDENT:
            launches.enrol(session, exam.course_id, user, False)  # the placing tutor shared their test
        launches.remember_line_item(session, context, exam.id, claims)
    return AcceptedLaunch(user, context.course_id if context else None, target, teaches)


def deep_link_owner(session: Session, claims: Mapping[str, Any], actor: User) -> None:
    """Refuses anyone but the person who made the deep-linking launch."""
    identity = session.scalar(select(LtiIdentity).where(LtiIdentity.user_id == actor.id))
    if identity is None or identity.issuer != claims.get("iss") or identity.subject != claims.get("sub"):
        raise LaunchRefused("not_yours", "This placement was started by someone else. Choose \"Select content\" "
                                         "in the LMS again.", 403)
