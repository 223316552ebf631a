"""A checked launch accepted: the person, the course, the enrolments and the placed target, in the request's unit
of work (a refusal anywhere discards all of it)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.errors import Refused
from middleware.exercises.services import course_marks
from middleware.lti import grades, launches
from middleware.lti.flow import ValidatedLaunch
from middleware.lti.launches import LaunchRefused, Target
from middleware.models import Role, User
from middleware.models.assessment import Exam
from middleware.models.exercises import Exercise, ExerciseAssignment
from middleware.models.lti import LtiContext, LtiIdentity, LtiPlatform


@dataclass(frozen=True)
class AcceptedLaunch:
    """Who launched, into which Telelab course, to open what; choose_course: an instructor's first launch from a new
    LMS course, who chooses one of their courses or a new one for it before going on."""

    user: User
    course_id: int | None
    target: Target | None
    teaches: bool
    choose_course: bool = False


def accept_launch(session: Session, validated: ValidatedLaunch, secret: str) -> AcceptedLaunch:
    """Matches or makes the person and the course, enrols, and reads the placed target."""
    claims = validated.claims
    teaches = launches.is_teacher(claims.get(launches.ROLES_CLAIM))
    if validated.is_deep_link and not teaches:
        raise LaunchRefused("not_instructor", gettext("Only the LMS course's instructors place Telelab content."), 403)
    user = launches.match_user(session, validated.platform.issuer, claims, teaches)
    target = None if validated.is_deep_link else launches.read_target(claims, secret)
    if teaches and launches.is_new_context(session, validated.platform, claims) and \
            launches.linkable_courses(session, user):
        return AcceptedLaunch(user, None, target, teaches, choose_course=True)
    context = launches.map_context(session, validated.platform, claims)
    return _open(session, claims, user, context, target, teaches)


def link_new_context(session: Session, claims: Mapping[str, Any], platform: LtiPlatform, actor: User, choice: str,
                     secret: str) -> AcceptedLaunch:
    """The instructor's choice for their new LMS course: choice is the id of one of their courses not linked yet,
    or "new" (a course made for it)."""
    _same_person(session, claims, actor, gettext("This launch was started by someone else. Open Telelab from the "
                                                 "LMS again."))
    course_id = None
    if choice != "new":
        linkable = {course.id for course in launches.linkable_courses(session, actor)}
        if not choice.isdigit() or int(choice) not in linkable:
            raise Refused(400, "invalid_field", gettext("Choose one of your courses, or a new course."), "course")
        course_id = int(choice)
    launch_claims = dict(claims)
    context = launches.map_context(session, platform, launch_claims, course_id)
    is_deep_link = launch_claims.get(launches.CLAIM + "message_type") == "LtiDeepLinkingRequest"
    target = None if is_deep_link else launches.read_target(launch_claims, secret)
    return _open(session, launch_claims, actor, context, target, True)


def _open(session: Session, claims: dict[str, Any], user: User, context: LtiContext | None, target: Target | None,
          teaches: bool) -> AcceptedLaunch:
    """Enrols user in the launch's course and checks the target it opens."""
    if context is not None:
        launches.enrol(session, context.course_id, user, teaches)
    if target is not None and target.kind == "exam":
        exam = session.get(Exam, int(target.key)) if target.key.isdigit() else None
        if exam is None:
            raise LaunchRefused("unknown_target", gettext("This test no longer exists in Telelab. Ask your "
                                                          "tutor."), 404)
        if not teaches and user.role == Role.STUDENT:
            launches.enrol(session, exam.course_id, user, False)  # the placing tutor shared their test
        launches.remember_line_item(session, context, claims, exam_id=exam.id)
    if target is not None and target.kind == "exercise" and context is not None:
        _remember_exercise_line_item(session, context, target.key, claims)
    return AcceptedLaunch(user, context.course_id if context else None, target, teaches)


def _remember_exercise_line_item(session: Session, context: LtiContext, slug: str, claims: dict[str, Any]) -> None:
    """Keeps the line item of a placed exercise that is a test of the LMS course's Telelab course; the LMS naming
    it for the first time gets the marks students already have."""
    test = session.scalar(select(ExerciseAssignment).join(Exercise, Exercise.id == ExerciseAssignment.exercise_id)
                          .where(ExerciseAssignment.course_id == context.course_id, Exercise.slug == slug[:64]))
    if test is None:
        return  # not a test of this course: a link to practise, with no column
    item = launches.remember_line_item(session, context, claims, exercise_assignment_id=test.id)
    if item is not None:
        grades.queue_marks_of_new_line_item(session, item, test, course_marks(session, test))


def _same_person(session: Session, claims: Mapping[str, Any], actor: User, refusal: str) -> None:
    identity = session.scalar(select(LtiIdentity).where(LtiIdentity.user_id == actor.id))
    if identity is None or identity.issuer != claims.get("iss") or identity.subject != claims.get("sub"):
        raise LaunchRefused("not_yours", refusal, 403)


def deep_link_owner(session: Session, claims: Mapping[str, Any], actor: User) -> None:
    """Refuses anyone but the person who made the deep-linking launch."""
    _same_person(session, claims, actor, gettext("This placement was started by someone else. Choose \"Select "
                                                 "content\" in the LMS again."))
