"""Names and Role Provisioning Services: a tutor syncs the course's roster from the LMS.

Active members are matched or created by issuer + subject and enrolled as their LMS role says; students the LMS
no longer lists as active (and whom the LMS made: an LtiIdentity of its issuer) leave the course. Local accounts
enrolled by hand are never touched.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import requests
from flask_babel import gettext  # type: ignore[import-untyped]
from pylti1p3.exception import LtiException
from pylti1p3.names_roles import NamesRolesProvisioningService
from sqlalchemy import delete, select
from sqlalchemy.orm import Session

from middleware.courses.authority import teaches_course
from middleware.errors import Refused
from middleware.lti import launches, services
from middleware.models import CourseMembership, User
from middleware.models.accounts import utc_now
from middleware.models.lti import LtiContext, LtiIdentity, LtiPlatform

MEMBERSHIP_SCOPE = "https://purl.imsglobal.org/spec/lti-nrps/scope/contextmembership.readonly"
MAX_MEMBERS = 5000


@dataclass(frozen=True)
class RosterReport:
    """What a sync did."""

    enrolled: int
    already: int
    removed: int

    def sentence(self) -> str:
        """The tutor's summary."""
        return str(gettext("Roster synced from the LMS: %(enrolled)s enrolled, %(already)s already here, "
                           "%(removed)s removed (no longer active in the LMS).", enrolled=self.enrolled,
                           already=self.already, removed=self.removed))


def linked_context(session: Session, course_id: int) -> LtiContext | None:
    """The LMS course mapped to this Telelab course, if any."""
    return session.scalar(select(LtiContext).where(LtiContext.course_id == course_id))


def _fetch(session: Session, context: LtiContext, http: requests.Session | None) -> list[dict[str, Any]]:
    platform = session.get(LtiPlatform, context.platform_id)
    if platform is None or not context.memberships_url:
        raise Refused(409, "no_roster_service", gettext("The LMS has not offered its roster to Telelab for this "
                                                        "course (no Names and Role Provisioning service in its "
                                                        "launches)."))
    nrps = NamesRolesProvisioningService(services.connector(session, platform, http),
                                         {"context_memberships_url": context.memberships_url,
                                          "service_versions": ["2.0"]})  # type: ignore[typeddict-unknown-key]
    try:
        members = nrps.get_members()
    except (LtiException, requests.RequestException, ValueError) as error:
        answer = services.lms_answer(error)
        raise Refused(502, "lms_unreachable", gettext("The roster could not be read: %(reason)s",
                                                      reason=services.said(answer) if answer else str(error)[:200])) \
            from None
    return [dict(m) for m in members if isinstance(m, dict)][:MAX_MEMBERS]


def sync(session: Session, actor: User, course_id: int, http: requests.Session | None = None) -> RosterReport:
    """Reads the LMS roster of the course and enrols or removes its people (the course's tutors, admins)."""
    if not teaches_course(session, actor, course_id):
        raise Refused(403, "forbidden", gettext("Only the course's tutors sync its roster."))
    context = linked_context(session, course_id)
    if context is None:
        raise Refused(409, "not_from_lms", gettext("This course is not linked to an LMS course: launch Telelab "
                                                   "from the LMS course once to link it."))
    members = _fetch(session, context, http)
    enrolled = already = 0
    active_users: set[int] = set()
    for member in members:
        subject = member.get("user_id")
        if not isinstance(subject, str) or not subject or member.get("status", "Active") != "Active":
            continue
        claims = {"sub": subject, "name": member.get("name"), "given_name": member.get("given_name")}
        teaches = launches.is_teacher(member.get("roles"))
        user = launches.match_user(session, context.issuer, claims, teaches)
        active_users.add(user.id)
        before = session.scalar(select(CourseMembership.id).where(CourseMembership.course_id == course_id,
                                                                  CourseMembership.user_id == user.id))
        launches.enrol(session, course_id, user, teaches)
        if before is not None:
            already += 1
        elif session.scalar(select(CourseMembership.id).where(CourseMembership.course_id == course_id,
                                                              CourseMembership.user_id == user.id)) is not None:
            enrolled += 1
    from_lms = select(LtiIdentity.user_id).where(LtiIdentity.issuer == context.issuer)
    gone = list(session.scalars(select(CourseMembership.id).where(
        CourseMembership.course_id == course_id, CourseMembership.role == "student",
        CourseMembership.user_id.in_(from_lms), CourseMembership.user_id.not_in(active_users or {-1}))))
    if gone:
        session.execute(delete(CourseMembership).where(CourseMembership.id.in_(gone)))
    context.roster_synced_at = utc_now()
    session.flush()
    return RosterReport(enrolled, already, len(gone))
