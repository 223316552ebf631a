"""What a validated launch does: the person (matched by issuer + subject only), their role, the LMS course
(mapped to a Telelab course, enrolled on every launch) and the page the launch opens.

Roles: an Instructor (or teaching assistant) of the LMS course is a tutor of its Telelab course and gets a tutor
account; anyone else there a student. An LMS administrator is never a lab admin: institution and system roles
are ignored. A tutor or admin account is never enrolled as a student (courses' rule), and an account is never
made less than it is.
"""

from __future__ import annotations

import hashlib
import hmac
import re
import secrets
from dataclasses import dataclass
from typing import Any

from flask_babel import gettext, lazy_gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware.auth.services import hash_password
from middleware.courses.authority import taught_course_ids
from middleware.errors import Refused
from middleware.models import Course, CourseMembership, Role, User
from middleware.models.lti import LtiContext, LtiIdentity, LtiLineItem, LtiPlatform

CLAIM = "https://purl.imsglobal.org/spec/lti/claim/"
ROLES_CLAIM = CLAIM + "roles"
CONTEXT_CLAIM = CLAIM + "context"
CUSTOM_CLAIM = CLAIM + "custom"
PRESENTATION_CLAIM = CLAIM + "launch_presentation"
AGS_CLAIM = "https://purl.imsglobal.org/spec/lti-ags/claim/endpoint"
NRPS_CLAIM = "https://purl.imsglobal.org/spec/lti-nrps/claim/namesroleservice"
TEACHING_ROLES = ("#Instructor", "#TeachingAssistant", "Instructor#TeachingAssistant", "#ContentDeveloper")
TARGET_PARAM = "telelab_target"
SIGNATURE_PARAM = "telelab_sig"
_TARGET = re.compile(r"^(console|pool|lesson|tour|exam|class|exercise):([A-Za-z0-9_.-]{0,64})$")


class LaunchRefused(Refused):
    """A launch that is refused: nothing is created, the page says why and what to do."""

    def __init__(self, code: str, message: str, status: int = 400) -> None:
        super().__init__(status, code, message)


def is_teacher(roles: object) -> bool:
    """True when the LMS roles say the person teaches the LMS course (never from an institution/system role)."""
    if not isinstance(roles, list):
        return False
    return any(isinstance(r, str) and "/membership" in r and r.endswith(TEACHING_ROLES) for r in roles) or \
        any(r in ("Instructor", "TeachingAssistant") for r in roles)


def check_audience(claims: dict[str, Any], client_id: str) -> None:
    """The token is for this tool: aud holds its client id, and azp names it when aud holds several."""
    aud = claims.get("aud")
    audiences = aud if isinstance(aud, list) else [aud]
    if client_id not in audiences or (len(audiences) > 1 and claims.get("azp") != client_id):
        raise LaunchRefused("wrong_audience", gettext("This launch was meant for another tool (its audience is "
                                                      "not Telelab's client id). Ask the LMS's administrator to "
                                                      "check the registration."))


def _slug(text: object, fallback: str) -> str:
    value = re.sub(r"[^a-z0-9._-]+", "-", str(text or "").lower()).strip("-._")
    return value[:40] or fallback


def _free_username(session: Session, base: str, salt: str) -> str:
    for attempt in range(20):
        suffix = hashlib.sha256(f"{salt}:{attempt}".encode()).hexdigest()[:6]
        name = f"{base}-{suffix}"[:64]
        if session.scalar(select(User.id).where(User.username == name)) is None:
            return name
    return f"lti-{secrets.token_hex(8)}"


def match_user(session: Session, issuer: str, claims: dict[str, Any], teaches: bool) -> User:
    """The account of (issuer, sub), made on the first launch; a tutor of the LMS course gets a tutor account."""
    subject = claims.get("sub")
    if not isinstance(subject, str) or not subject or len(subject) > 255:
        raise LaunchRefused("missing_claims", gettext("The launch names no person (its sub claim is missing)."))
    identity = session.scalar(select(LtiIdentity).where(LtiIdentity.issuer == issuer,
                                                        LtiIdentity.subject == subject))
    if identity is not None:
        user = session.get(User, identity.user_id)
        assert user is not None  # the foreign key cascades
        if not user.is_active:
            raise LaunchRefused("disabled", gettext("Your Telelab account is disabled. Ask the lab's "
                                                    "administrator."), 403)
        if teaches and user.role == Role.STUDENT:
            user.role = Role.TUTOR.value  # never less than it is, never admin
        return user
    base = _slug(claims.get("given_name") or claims.get("name"), "lti")
    user = User(username=_free_username(session, base, f"{issuer}|{subject}"),
                role=(Role.TUTOR if teaches else Role.STUDENT).value,
                password_hash=hash_password(secrets.token_urlsafe(32)))  # no password login: the LMS signs in
    session.add(user)
    session.flush()
    session.add(LtiIdentity(issuer=issuer, subject=subject, user_id=user.id))
    session.flush()
    return user


def _free_code(session: Session, label: str, salt: str) -> str:
    base = _slug(label, "lms").upper()[:24]
    if session.scalar(select(Course.id).where(Course.code == base)) is None:
        return base
    return f"{base}-{hashlib.sha256(salt.encode()).hexdigest()[:6]}".upper()[:32]


def _context_id(claims: dict[str, Any]) -> tuple[str, dict[str, Any]] | None:
    """(the LMS course's id, its claim), None for a launch from no LMS course."""
    context = claims.get(CONTEXT_CLAIM)
    if not isinstance(context, dict):
        return None
    context_id = context.get("id")
    if not isinstance(context_id, str) or not context_id or len(context_id) > 255:
        raise LaunchRefused("missing_claims", gettext("The launch's course (context) has no id."))
    return context_id, context


def is_new_context(session: Session, platform: LtiPlatform, claims: dict[str, Any]) -> bool:
    """True when the launch comes from an LMS course Telelab has no course for yet."""
    found = _context_id(claims)
    return found is not None and session.scalar(select(LtiContext.id).where(
        LtiContext.issuer == platform.issuer, LtiContext.context_id == found[0])) is None


def linkable_courses(session: Session, user: User) -> list[Course]:
    """The courses user tutors that no LMS course is linked to yet (one LMS course per Telelab course)."""
    linked = select(LtiContext.course_id)
    return list(session.scalars(select(Course).where(Course.id.in_(taught_course_ids(user)), Course.id.not_in(linked))
                                .order_by(Course.title, Course.id)))


def context_course(session: Session, claims: dict[str, Any]) -> int | None:
    """The Telelab course of a launch's LMS course, None when it has none (yet)."""
    found = _context_id(claims)
    return None if found is None else session.scalar(select(LtiContext.course_id).where(
        LtiContext.issuer == claims.get("iss"), LtiContext.context_id == found[0]))


def map_context(session: Session, platform: LtiPlatform, claims: dict[str, Any],
                course_id: int | None = None) -> LtiContext | None:
    """The Telelab course of the launch's LMS course, with the service URLs it gave. On its first launch the LMS
    course is linked to course_id (an existing course the caller checked), or to a new course made for it."""
    found = _context_id(claims)
    if found is None:
        return None
    context_id, context = found
    row = session.scalar(select(LtiContext).where(LtiContext.issuer == platform.issuer,
                                                  LtiContext.context_id == context_id))
    if row is None:
        if course_id is None:
            label = context.get("label") or context.get("title") or "LMS"
            title = str(context.get("title") or label)[:200]
            course = Course(code=_free_code(session, str(label), f"{platform.issuer}|{context_id}"), title=title)
            session.add(course)
            session.flush()
            course_id = course.id
        row = LtiContext(platform_id=platform.id, issuer=platform.issuer, context_id=context_id,
                         course_id=course_id, ags_scopes=[])
        session.add(row)
        try:
            session.flush()
        except IntegrityError:  # another launch linked this LMS course, or another one to that course, meanwhile
            raise LaunchRefused("already_linked", lazy_gettext(
                "That course was linked to an LMS course at the same moment. Launch Telelab from the LMS again."),
                409) from None
    nrps = claims.get(NRPS_CLAIM)
    if isinstance(nrps, dict) and isinstance(nrps.get("context_memberships_url"), str):
        row.memberships_url = nrps["context_memberships_url"][:1000]
    ags = claims.get(AGS_CLAIM)
    if isinstance(ags, dict):
        if isinstance(ags.get("lineitems"), str):
            row.lineitems_url = ags["lineitems"][:1000]
        if isinstance(ags.get("scope"), list):
            row.ags_scopes = [s for s in ags["scope"] if isinstance(s, str)][:10]
    session.flush()
    return row


def enrol(session: Session, course_id: int, user: User, teaches: bool) -> None:
    """Enrols user in the course as the launch says; a tutor account is never made a student, nor a tutor of the
    course a student (an LMS student who was once an instructor elsewhere stays a student here)."""
    role = "tutor" if teaches and user.role != Role.STUDENT else "student"
    if role == "student" and user.role != Role.STUDENT:
        return  # a tutor or admin account sees the course by its role; never a student member
    membership = session.scalar(select(CourseMembership).where(CourseMembership.course_id == course_id,
                                                               CourseMembership.user_id == user.id))
    if membership is None:
        session.add(CourseMembership(course_id=course_id, user_id=user.id, role=role))
        session.flush()


def sign_target(secret: str, context_id: str, target: str) -> str:
    """The signature that says Telelab placed this target in this LMS course (its deep-link response)."""
    return hmac.new(secret.encode(), f"{context_id}|{target}".encode(), hashlib.sha256).hexdigest()[:32]


@dataclass(frozen=True)
class Target:
    """What a placed link opens: console:lab-1, pool:<kind>, lesson:<id>, tour:<id>, exam:<id>, exercise:<slug>,
    class:."""

    kind: str
    key: str


def read_target(claims: dict[str, Any], secret: str) -> Target | None:
    """The target Telelab placed (custom parameters, signed for this LMS course), None for the lab's home."""
    custom = claims.get(CUSTOM_CLAIM)
    if not isinstance(custom, dict) or TARGET_PARAM not in custom:
        return None
    target, signature = custom.get(TARGET_PARAM), custom.get(SIGNATURE_PARAM)
    context = claims.get(CONTEXT_CLAIM)
    context_id = context.get("id") if isinstance(context, dict) else ""
    match = _TARGET.fullmatch(target) if isinstance(target, str) else None
    if match is None or not isinstance(signature, str) or not hmac.compare_digest(
            signature, sign_target(secret, str(context_id), str(target))):
        raise LaunchRefused("unknown_target", gettext("This link was not placed by Telelab in this LMS course. Ask "
                                                      "your tutor to place it again with \"Select content\"."))
    return Target(match.group(1), match.group(2))


def remember_line_item(session: Session, context: LtiContext | None, claims: dict[str, Any], *,
                       exam_id: int | None = None, exercise_assignment_id: int | None = None) -> LtiLineItem | None:
    """Keeps the LMS line item the launch of a placed test (exam_id) or exercise test (exercise_assignment_id)
    names, where its grades go; the row when the LMS named it for the first time, else None."""
    ags = claims.get(AGS_CLAIM)
    url = ags.get("lineitem") if isinstance(ags, dict) else None
    if context is None or not isinstance(url, str) or not url.startswith(("https://", "http://")):
        return None
    graded = LtiLineItem.exam_id == exam_id if exam_id is not None else \
        LtiLineItem.exercise_assignment_id == exercise_assignment_id
    row = session.scalar(select(LtiLineItem).where(LtiLineItem.context_id == context.id, graded))
    if row is not None:
        row.lineitem_url = url[:1000]
        session.flush()
        return None
    row = LtiLineItem(context_id=context.id, exam_id=exam_id, exercise_assignment_id=exercise_assignment_id,
                      lineitem_url=url[:1000])
    try:
        with session.begin_nested():
            session.add(row)
    except IntegrityError:  # another launch named it at the same moment: it is known, and its marks queued there
        return None
    return row
