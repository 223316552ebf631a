"""Tours: checking a tour's steps, storing them, and the live guided sessions (who leads, which step, who drives).

The fully guided step engine runs in the learner's browser (client_ui/static/pages/teaching/tour-engine.js, a pure state
machine); the server checks every step here and runs a step's command only as stored.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from datetime import datetime

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.errors import Refused, written_number
from middleware.models.accounts import utc_now
from middleware.models.teaching import GuidedSession, Tour
from middleware.teaching.command_form import CommandInvalid, RobotCommand, SkillSchemas, parse_command
from middleware.teaching.lessons import normalise_topics, topic_list

PANEL_ID = re.compile(r"^[a-z][a-z0-9_-]{0,63}$")
SLUG = re.compile(r"^[a-z0-9][a-z0-9-]{0,63}$")
MAX_STEPS = 50
MAX_TEXT = 2000
MIN_WAIT_S, MAX_WAIT_S = 0.5, 600.0
CONDITIONS = ("skill_finished", "time", "manual")


class TourInvalid(Refused, ValueError):
    """A tour that cannot be saved (400 invalid_tour); field names the part ("steps[2].condition.seconds")."""

    field: str

    def __init__(self, field: str, message: str) -> None:
        super().__init__(400, "invalid_tour", message, field)


@dataclass(frozen=True)
class TourStep:
    """One checked step."""

    title: str
    text: str
    panel: str
    command: RobotCommand | None
    condition: str
    seconds: float

    def to_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        condition: dict[str, object] = {"type": self.condition}
        if self.condition == "time":
            condition["seconds"] = self.seconds
        return {"title": self.title, "text": self.text, "panel": self.panel,
                "command": self.command.to_dict() if self.command else None, "condition": condition}


def _text(value: object, field: str, limit: int, required: bool) -> str:
    if value is None and not required:
        return ""
    if not isinstance(value, str):
        raise TourInvalid(field, gettext("%(field)s must be text.", field=field))
    value = value.strip()
    if required and not value:
        raise TourInvalid(field, gettext("%(field)s must not be empty.", field=field))
    if len(value) > limit:
        raise TourInvalid(field, gettext("%(field)s has at most %(limit)s characters.", field=field, limit=limit))
    return value


def parse_step(value: object, at: str, skills: SkillSchemas | None) -> TourStep:
    """One step from its JSON form: title, text, panel, command (optional), condition."""
    if not isinstance(value, dict):
        raise TourInvalid(at, gettext("%(at)s must be an object with text, panel and condition.", at=at))
    unknown = set(value) - {"title", "text", "panel", "command", "condition"}
    if unknown:
        raise TourInvalid(f"{at}.{sorted(unknown)[0][:40]}", gettext("Unknown key %(key)s in %(at)s.",
                                                                      key=repr(sorted(unknown)[0][:40]), at=at))
    title = _text(value.get("title"), f"{at}.title", 120, required=False)
    text = _text(value.get("text"), f"{at}.text", MAX_TEXT, required=True)
    panel = value.get("panel")
    if not isinstance(panel, str) or not PANEL_ID.fullmatch(panel):
        raise TourInvalid(f"{at}.panel", gettext("panel must be a panel id such as camera, map or skill-go_to_goal."))
    command = None
    if value.get("command") is not None:
        try:
            command = parse_command(value["command"], skills)
        except CommandInvalid as invalid:
            raise TourInvalid(f"{at}.command.{invalid.field}", invalid.message) from None
    condition = value.get("condition", {"type": "manual"})
    if not isinstance(condition, dict) or condition.get("type") not in CONDITIONS:
        raise TourInvalid(f"{at}.condition", gettext('condition must be {"type": "skill_finished"}, '
                                                     '{"type": "time", "seconds": n} or {"type": "manual"}.'))
    kind = condition["type"]
    seconds = 0.0
    if kind == "time":
        raw = condition.get("seconds")
        if isinstance(raw, bool) or not isinstance(raw, int | float) or not MIN_WAIT_S <= raw <= MAX_WAIT_S:
            raise TourInvalid(f"{at}.condition.seconds",
                              gettext("seconds must be a number from %(low)s to %(high)s.",
                                      low=written_number(MIN_WAIT_S, "g"), high=written_number(MAX_WAIT_S, "g")))
        seconds = float(raw)
    if kind == "skill_finished" and (command is None or command.kind != "skill"):
        raise TourInvalid(f"{at}.condition", gettext("'skill finished' needs the step to run a skill."))
    return TourStep(title, text, panel, command, kind, seconds)


def parse_steps(value: object, skills: SkillSchemas | None) -> list[TourStep]:
    """Every step of a tour, checked; the first problem is raised with its field."""
    if not isinstance(value, list) or not 1 <= len(value) <= MAX_STEPS:
        raise TourInvalid("steps", gettext("A tour has 1 to %(max_steps)s steps.", max_steps=MAX_STEPS))
    return [parse_step(step, f"steps[{i}]", skills) for i, step in enumerate(value)]


def check_tour(data: object, skills: SkillSchemas | None) -> tuple[str, str, str, list[TourStep]]:
    """(slug, title, summary, steps) of the editor's JSON, checked."""
    if not isinstance(data, dict):
        raise TourInvalid("body", gettext("Send a JSON object with title, summary and steps."))
    title = _text(data.get("title"), "title", 120, required=True)
    summary = _text(data.get("summary"), "summary", 500, required=False)
    slug = data.get("slug") or re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")[:64] or "tour"
    if not isinstance(slug, str) or not SLUG.fullmatch(slug):
        raise TourInvalid("slug", gettext("slug may use lower-case letters, digits and '-' (at most 64)."))
    return slug, title, summary, parse_steps(data.get("steps"), skills)


def save_tour(session: Session, data: object, skills: SkillSchemas | None, author_id: int | None,
              tour: Tour | None = None) -> Tour:
    """Creates or updates a tour from the editor's JSON (topics optional: "a, b"); the caller commits."""
    slug, title, summary, steps = check_tour(data, skills)
    try:
        topics = normalise_topics(data.get("topics") if isinstance(data, dict) else None)
    except ValueError as error:
        raise TourInvalid("topics", str(error)) from None
    clash = session.scalar(select(Tour).where(Tour.slug == slug))
    if clash is not None and clash is not tour:
        raise TourInvalid("slug", gettext("Another tour is called %(slug)s already.", slug=repr(slug)))
    if tour is None:
        tour = Tour(author_id=author_id)
        session.add(tour)
    tour.slug, tour.title, tour.summary, tour.topics = slug, title, summary, topics
    tour.steps_json = json.dumps([s.to_dict() for s in steps])
    tour.updated_at = utc_now()
    session.flush()
    return tour


def tour_steps(tour: Tour) -> list[TourStep]:
    """The stored steps (checked on save; re-read without a schema)."""
    return parse_steps(json.loads(tour.steps_json), None)


def tour_dict(tour: Tour) -> dict[str, object]:
    """JSON-ready form."""
    return {"id": tour.id, "slug": tour.slug, "title": tour.title, "summary": tour.summary,
            "topics": topic_list(tour.topics), "steps": [s.to_dict() for s in tour_steps(tour)]}


# --- live guided sessions ----------------------------------------------------------------------


def active_session(session: Session, robot_name: str) -> GuidedSession | None:
    """The guided session running on robot_name, if any."""
    return session.scalar(select(GuidedSession).where(GuidedSession.robot_name == robot_name,
                                                      GuidedSession.ended_at.is_(None))
                          .order_by(GuidedSession.id.desc()).limit(1))


def robots_in_live_classes(session: Session) -> set[str]:
    """Every robot a guided session runs on now (with_guided_priority may speak only of these)."""
    return set(session.scalars(select(GuidedSession.robot_name).where(GuidedSession.ended_at.is_(None))))


def start_session(session: Session, tour: Tour, robot_name: str, tutor_id: int, course_id: int | None,
                  now: datetime, priority_override_by_id: int | None = None) -> GuidedSession:
    """Starts a live class (ending any earlier one on the robot); the caller checked teaching/authority.py.

    The class goes before the queue only as with_guided_priority allows: in the leader's booked slot, or with
    an admin's override (priority_override_by_id, recorded on the class).
    """
    for old in session.scalars(select(GuidedSession).where(GuidedSession.robot_name == robot_name,
                                                           GuidedSession.ended_at.is_(None))):
        old.ended_at = now
    live = GuidedSession(tour_id=tour.id, robot_name=robot_name, tutor_id=tutor_id, course_id=course_id,
                         step_index=0, control_user_id=tutor_id, version=1, started_at=now,
                         priority_override_by_id=priority_override_by_id)
    session.add(live)
    session.flush()
    return live


def go_to_step(live: GuidedSession, index: int, step_count: int) -> None:
    """The tutor moves the class to step index."""
    if not 0 <= index < step_count:
        raise TourInvalid("index", gettext("index must be from 0 to %(last)s.", last=step_count - 1))
    live.step_index = index
    live.version += 1


def hand_control(live: GuidedSession, user_id: int | None) -> None:
    """Gives the robot to user_id (a student), or back to the tutor with None."""
    live.control_user_id = user_id if user_id is not None else live.tutor_id
    live.version += 1


def end_session(live: GuidedSession, now: datetime) -> None:
    """Ends the class; the robot's queue goes back to the usual rule."""
    live.ended_at = now
    live.version += 1


def with_guided_priority(fallback: Callable[[Session, str, datetime], int | None]
                         ) -> Callable[[Session, str, datetime], int | None]:
    """A priority rule that extends fallback (the bookings rule) instead of outranking it: while a live class
    runs in its leader's booked slot, or under an admin's recorded override, the class's controller (the
    leader or the student handed control) has the robot first; otherwise fallback decides, so a class with
    neither takes the robot only in turn, never from a student mid-turn."""

    def priority(session: Session, robot_name: str, now: datetime) -> int | None:
        booked = fallback(session, robot_name, now)
        live = active_session(session, robot_name)
        if live is not None and (booked == live.tutor_id or live.priority_override_by_id is not None):
            return live.control_user_id or live.tutor_id
        return booked

    return priority


def panel_choices(console_panels: list[dict[str, object]], skill_names: Iterable[str],
                  in_use: Iterable[str]) -> list[tuple[str, str]]:
    """(id, title) of the panels a tour step may name: the console's own panels, one per skill, and any panel
    the tour names already (so editing never drops a choice)."""
    choices = {str(p["id"]): str(p["title"]) for p in console_panels if p.get("kind") != "skill"}
    for name in sorted(skill_names):
        choices.setdefault(f"skill-{name}", name.replace("_", " ").capitalize())
    for panel_id in in_use:
        choices.setdefault(panel_id, panel_id)
    return list(choices.items())
