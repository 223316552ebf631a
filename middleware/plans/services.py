"""The rules of stored plans: who reads, edits, copies and shares which plan, and how every save becomes a version.

A plan is its owner's. Shared with a course (only by a tutor who teaches it, or an admin), it is readable by the
course's members, who may copy it into their own plans but not change it (403). Anyone else is answered as if it
did not exist (404). Services take the session and the acting user, flush, and raise a Refused.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import ColumnElement, delete, exists, func, or_, select
from sqlalchemy.orm import Session

from middleware.courses.authority import teaches_course
from middleware.errors import Refused
from middleware.models import Course, CourseMembership, Role, User
from middleware.models.accounts import utc_now
from middleware.models.plans import PlanVersion, StoredPlan
from middleware.plans.language import (
    Plan,
    SkillSchemas,
    parse_plan_text,
    plan_from_json,
    plan_summary,
    plan_to_json,
    plan_to_text,
)
from middleware.plans.schemas import PlanFile

MAX_PLANS_PER_USER = 200
MAX_VERSIONS_KEPT = 200  # the oldest go beyond this; a plan saved this often has its history in its latest text


class PlanRefused(Refused):
    """A plan action refused: 404 unknown_plan, 403 read_only or forbidden, 409 name_taken or too_many_plans."""


def unknown_plan(field: str = "plan_id") -> PlanRefused:
    """The one answer for a plan that does not exist or is someone else's private plan."""
    return PlanRefused(404, "unknown_plan", gettext("There is no plan with that id."), field)


@dataclass(frozen=True)
class CheckedPlan:
    """A checked plan as it is stored: the text as written, the canonical JSON and the summary (JSON text)."""

    text: str
    canonical_json: str
    summary_json: str

    @classmethod
    def of(cls, plan: Plan, text: str) -> CheckedPlan:
        """plan, stored beside the text it was read from."""
        return cls(text, json.dumps(plan_to_json(plan), separators=(",", ":")),
                   json.dumps(plan_summary(plan), separators=(",", ":")))

    def document(self) -> object:
        """The canonical JSON, decoded."""
        return json.loads(self.canonical_json)

    def summary(self) -> object:
        """The summary, decoded."""
        return json.loads(self.summary_json)


def check_text(text: str, skills: SkillSchemas) -> CheckedPlan:
    """The plan written in text (PlanInvalid with every error otherwise)."""
    return CheckedPlan.of(parse_plan_text(text, skills), text)


def check_file(upload: PlanFile, skills: SkillSchemas) -> CheckedPlan:
    """The plan in an imported file; a JSON file's text is written from the plan."""
    if upload.text is not None:
        return check_text(upload.text, skills)
    plan = plan_from_json(upload.document, skills)
    return CheckedPlan.of(plan, plan_to_text(plan))


def _shared_with(user: User) -> ColumnElement[bool]:
    member_of = select(CourseMembership.course_id).where(CourseMembership.user_id == user.id)
    return StoredPlan.shared_course_id.in_(member_of)


def readable_plan(session: Session, user: User, plan_id: int) -> StoredPlan:
    """The plan if user may read it: its owner, a member of the course it is shared with, or an admin; else 404."""
    plan = session.get(StoredPlan, plan_id)
    if plan is None:
        raise unknown_plan()
    if plan.owner_id == user.id or user.role == Role.ADMIN:
        return plan
    if plan.shared_course_id is not None and session.scalar(select(exists().where(
            CourseMembership.user_id == user.id, CourseMembership.course_id == plan.shared_course_id))):
        return plan
    raise unknown_plan()


def owned_plan(session: Session, user: User, plan_id: int, *, lock: bool = False) -> StoredPlan:
    """The plan if user owns it; 404 if they may not read it, 403 read_only if it is shared with them."""
    plan = readable_plan(session, user, plan_id)
    if plan.owner_id != user.id:
        raise PlanRefused(403, "read_only", gettext("This plan is shared with you to read and run: copy it into "
                                                    "your own plans to change it."), "plan_id")
    if lock:
        session.refresh(plan, with_for_update=True)  # two saves at once number their versions one after the other
    return plan


def plan_version(session: Session, plan: StoredPlan, version: int | None) -> PlanVersion:
    """The plan's version (the latest when None); 404 naming version for one never saved or no longer kept."""
    number = plan.latest_version if version is None else version
    row = session.scalar(select(PlanVersion).where(PlanVersion.plan_id == plan.id, PlanVersion.version == number))
    if row is None:
        raise PlanRefused(404, "unknown_version", gettext("This plan has no version %(number)s.", number=number),
                          "version")
    return row


def _name_free(session: Session, owner_id: int, name: str, except_id: int | None = None) -> None:
    taken = session.scalar(select(StoredPlan.id).where(StoredPlan.owner_id == owner_id, StoredPlan.name == name))
    if taken is not None and taken != except_id:
        raise PlanRefused(409, "name_taken", gettext("You already have a plan named %(name)s: choose another name.",
                                                     name=name), "name")


def _add_version(session: Session, plan: StoredPlan, user: User, checked: CheckedPlan) -> PlanVersion:
    row = PlanVersion(plan_id=plan.id, version=plan.latest_version, text=checked.text,
                      canonical_json=checked.canonical_json, summary_json=checked.summary_json, saved_by_id=user.id)
    session.add(row)
    session.flush()
    return row


def create_plan(session: Session, user: User, name: str, checked: CheckedPlan) -> StoredPlan:
    """A new plan of user's, its first version holding checked."""
    _name_free(session, user.id, name)
    count = session.scalar(select(func.count()).select_from(StoredPlan).where(StoredPlan.owner_id == user.id)) or 0
    if count >= MAX_PLANS_PER_USER:
        raise PlanRefused(409, "too_many_plans", gettext("You have %(count)s plans, the most one person keeps: "
                                                         "delete some first.", count=MAX_PLANS_PER_USER), "name")
    plan = StoredPlan(owner_id=user.id, name=name, latest_version=1)
    session.add(plan)
    session.flush()
    _add_version(session, plan, user, checked)
    return plan


def save_plan(session: Session, user: User, plan_id: int, checked: CheckedPlan,
              name: str | None = None) -> StoredPlan:
    """A new version of user's plan (and a new name when given); the old versions stay readable."""
    plan = owned_plan(session, user, plan_id, lock=True)
    if name is not None and name != plan.name:
        _name_free(session, user.id, name, except_id=plan.id)
        plan.name = name
    plan.latest_version += 1
    plan.updated_at = utc_now()
    _add_version(session, plan, user, checked)
    oldest_kept = plan.latest_version - MAX_VERSIONS_KEPT
    if oldest_kept > 0:
        session.execute(delete(PlanVersion).where(PlanVersion.plan_id == plan.id, PlanVersion.version <= oldest_kept))
    return plan


def delete_plan(session: Session, user: User, plan_id: int) -> None:
    """Deletes user's plan with all its versions."""
    plan = owned_plan(session, user, plan_id)
    session.execute(delete(PlanVersion).where(PlanVersion.plan_id == plan.id))
    session.delete(plan)
    session.flush()


def copy_plan(session: Session, user: User, plan_id: int, name: str | None) -> StoredPlan:
    """A plan user may read, copied (its latest version) into user's own plans under name (or a free one)."""
    source = readable_plan(session, user, plan_id)
    latest = plan_version(session, source, None)
    if name is None:
        name = _free_name(session, user.id, source.name)
    return create_plan(session, user, name, CheckedPlan(latest.text, latest.canonical_json, latest.summary_json))


def _free_name(session: Session, owner_id: int, base: str) -> str:
    taken = set(session.scalars(select(StoredPlan.name).where(StoredPlan.owner_id == owner_id)))
    if base not in taken:
        return base
    for index in range(2, MAX_PLANS_PER_USER + 2):
        suffix = f"-{index}"
        candidate = base[:64 - len(suffix)] + suffix
        if candidate not in taken:
            return candidate
    raise PlanRefused(409, "name_taken", gettext("Choose a name for the copy."), "name")


def share_plan(session: Session, user: User, plan_id: int, course_id: int | None) -> StoredPlan:
    """Shares user's plan with a course they teach (read-only to its members), or stops sharing it (None)."""
    plan = owned_plan(session, user, plan_id)
    if course_id is not None:
        if user.role not in (Role.TUTOR, Role.ADMIN):
            raise PlanRefused(403, "forbidden", gettext("Only tutors share plans with a course."), "course_id")
        if session.get(Course, course_id) is None or not teaches_course(session, user, course_id):
            raise PlanRefused(404, "unknown_course", gettext("You teach no course with that id."), "course_id")
    plan.shared_course_id = course_id
    plan.updated_at = utc_now()
    session.flush()
    return plan


def use_as_skill(session: Session, user: User, plan_id: int, enabled: bool) -> StoredPlan:
    """Shows user's plan as a panel of its own in their consoles (or stops showing it)."""
    plan = owned_plan(session, user, plan_id)
    plan.console_skill = enabled
    session.flush()
    return plan


def console_skill_panels(session: Session, user_id: int, robot_name: str) -> list[dict[str, object]]:
    """The panel descriptors of user_id's plans used as skills, for the console of robot_name: a Run button that
    runs the plan's latest version there, and its line progress."""
    plans = session.scalars(select(StoredPlan).where(StoredPlan.owner_id == user_id, StoredPlan.console_skill)
                            .order_by(StoredPlan.name).limit(20))
    return [{"id": f"plan-{plan.id}", "kind": "plan", "title": f"Plan {plan.name}", "channel": None,
             "help": f"Your plan {plan.name} as a skill: Run starts its latest version on {robot_name}; the line "
                     "running shows below.",
             "tab": "navigate", "plan_id": plan.id, "plan_name": plan.name, "skill": f"plan:{plan.name}",
             "run_url": f"/api/plans/{plan.id}/runs", "editor_url": f"/plans/{plan.id}"} for plan in plans]


def visible_plans(session: Session, user: User) -> list[StoredPlan]:
    """user's own plans, then the plans shared with their courses, newest first."""
    query = select(StoredPlan).where(or_(StoredPlan.owner_id == user.id, _shared_with(user)))
    return list(session.scalars(query.order_by(StoredPlan.updated_at.desc(), StoredPlan.id.desc()).limit(1000)))


def versions_of(session: Session, plan: StoredPlan) -> list[tuple[int, object]]:
    """The versions kept, newest first, as (version, saved at)."""
    rows = session.execute(select(PlanVersion.version, PlanVersion.created_at).where(PlanVersion.plan_id == plan.id)
                           .order_by(PlanVersion.version.desc()))
    return [(number, saved_at) for number, saved_at in rows]


def plan_dict(session: Session, user: User, plan: StoredPlan, version: PlanVersion | None = None) -> dict[str, object]:
    """A plan as the API answers it; with version, its text, canonical JSON, summary and the versions kept."""
    owner = session.get(User, plan.owner_id)
    course = session.get(Course, plan.shared_course_id) if plan.shared_course_id is not None else None
    body: dict[str, object] = {
        "id": plan.id, "name": plan.name, "owner": owner.username if owner else None,
        "mine": plan.owner_id == user.id, "latest_version": plan.latest_version, "console_skill": plan.console_skill,
        "shared_with": None if course is None else {"id": course.id, "code": course.code, "title": course.title},
        "updated_at": plan.updated_at.isoformat(),
    }
    if version is not None:
        body.update({"version": version.version, "text": version.text,
                     "plan": json.loads(version.canonical_json), "summary": json.loads(version.summary_json),
                     "versions": [{"version": number, "saved_at": saved_at.isoformat()}  # type: ignore[attr-defined]
                                  for number, saved_at in versions_of(session, plan)]})
    return body


def export_json(version: PlanVersion) -> str:
    """A version's canonical JSON as an exported file (indented for people, read back by the import)."""
    return json.dumps(json.loads(version.canonical_json), indent=2) + "\n"


def stored_document(version: PlanVersion) -> dict[str, object]:
    """A version's canonical JSON (the export and the form a run re-checks against its robot)."""
    document = json.loads(version.canonical_json)
    assert isinstance(document, dict)
    return document
