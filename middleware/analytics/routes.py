"""The usage page, its figures as JSON, a CSV per figure, and a course's xAPI statements (tutors: their courses;
admins: all). Routes parse and answer; scope.py decides who reads what, figures.py and statements.py compute."""

from __future__ import annotations

import csv
import io
import json
from datetime import UTC, datetime, timedelta
from typing import Any

from flask import Blueprint, Response, current_app, render_template, request
from flask.typing import ResponseReturnValue
from flask_login import current_user, login_required

from middleware.analytics import analytics_of, figures, outbox, schemas, scope
from middleware.analytics.statements import StatementBuilder
from middleware.api.contract import (
    OBJECT,
    STRING,
    about,
    array,
    described,
    file_answer,
    nullable,
    obj,
    obj_of,
    one_of,
    whole,
)
from middleware.db import get_session
from middleware.models import Role, User

blueprint = Blueprint("analytics", __name__)
SESSIONS_SHOWN = 200
QUERY = {"course_id": whole(1, 2**63 - 1), "from": about("first day, YYYY-MM-DD (default: four weeks ago)"),
         "to": about("last day, YYYY-MM-DD (default: today)"),
         "utc_offset_min": whole(-schemas.MAX_OFFSET_MIN, schemas.MAX_OFFSET_MIN)}


def _user() -> User:
    return current_user._get_current_object()


def _now() -> datetime:
    return datetime.now(UTC)


def _request_scope() -> tuple[scope.Scope, schemas.Window]:
    """The scope and window the query asks for, refused (naming the field) before anything is read."""
    course_id = schemas.course_id(request.args)
    offset_window = schemas.window(request.args, (_now() + timedelta(minutes=_offset_guess())).date())
    return scope.resolve(get_session(), _user(), course_id), offset_window


def _offset_guess() -> int:
    """The viewer's offset for "today" (checked again by schemas.window)."""
    raw = request.args.get("utc_offset_min", "")
    return int(raw) if raw.lstrip("-").isdigit() and len(raw) <= 4 and abs(int(raw)) <= schemas.MAX_OFFSET_MIN else 0


@blueprint.get("/analytics")
@login_required
def page() -> ResponseReturnValue:
    """The usage page: the courses the viewer may read, the figures drawn by its script from the JSON."""
    actor = _user()
    scope.require_analyst(actor)
    courses = scope.analyzable_courses(get_session(), actor)
    return render_template("analytics/index.html", courses=courses, admin=actor.role == Role.ADMIN)


@blueprint.get("/api/analytics/usage")
@login_required
@described(query=QUERY, answers={200: obj(("window", "sessions", "students", "heat_map", "waits", "robots"),
                                          window=OBJECT, sessions=array(OBJECT), students=array(OBJECT),
                                          heat_map=array(array({"type": "number"})), waits=OBJECT,
                                          robots=array(OBJECT), course=nullable(OBJECT),
                                          sessions_total={"type": "integer"}, xapi=OBJECT)})
def usage() -> ResponseReturnValue:
    """Every figure of the scope and window: sessions (the newest 200, and how many in all), time on robots per
    student, the week-by-hour heat map (minutes), queue waits (summary and bins), robots' uptime and faults."""
    found, window = _request_scope()
    session, now = get_session(), _now()
    rows = figures.sessions(session, found, window)
    waits = [w.wait_s for w, _name in figures.queue_waits(session, found, window)]
    answer: dict[str, object] = {
        "window": window.to_dict(),
        "course": {"id": found.course.id, "code": found.course.code, "title": found.course.title}
        if found.course else None,
        "sessions": [r.to_dict(now) for r in rows[:SESSIONS_SHOWN]], "sessions_total": len(rows),
        "students": figures.time_per_student(session, found, window, rows, now),
        "heat_map": figures.heat_map(rows, window, now), "waits": figures.wait_summary(waits),
        "robots": figures.robots(session, window, rows, now),
    }
    if _user().role == Role.ADMIN:
        settings = analytics_of(current_app).sender.settings
        answer["xapi"] = {"lrs": settings.sends, **outbox.outbox_status(session)}
    return answer


def _csv_rows(report: str, found: scope.Scope, window: schemas.Window) -> list[list[Any]]:
    session, now = get_session(), _now()
    rows = figures.sessions(session, found, window)
    if report == "sessions":
        return [["session_id", "username", "robot", "kind", "started_at", "ended_at", "duration_s", "commands",
                 "skills", "plans", "ended_by"]] + [
            [d["id"], d["username"], d["robot_name"], d["kind"], d["started_at"], d["ended_at"] or "",
             d["duration_s"], d["command_count"], d["skill_count"], d["plan_count"], d["end_reason"] or ""]
            for d in (r.to_dict(now) for r in rows)]
    if report == "students":
        return [["username", "sessions", "seconds_on_robots"]] + [
            [s["username"], s["sessions"], s["seconds"]] for s in figures.time_per_student(session, found, window,
                                                                                           rows, now)]
    if report == "heatmap":
        days = ("monday", "tuesday", "wednesday", "thursday", "friday", "saturday", "sunday")
        return [["weekday", *[f"{h:02d}" for h in range(24)]]] + [
            [days[i], *minutes] for i, minutes in enumerate(figures.heat_map(rows, window, now))]
    if report == "waits":
        return [["username", "robot", "waited_from", "granted_at", "wait_s"]] + [
            [name, w.robot_name, w.waited_from.isoformat(), w.granted_at.isoformat(), round(w.wait_s, 1)]
            for w, name in figures.queue_waits(session, found, window)]
    header: list[Any] = ["robot", "sessions", "seconds_used", "outages", "downtime_s", "uptime_pct", "maintenance"]
    return [header] + [
        [r["robot_name"], r["sessions"], r["seconds_used"], r["outages"], r["downtime_s"],
         "" if r["uptime_pct"] is None else r["uptime_pct"],
         " ".join(f"{k}={v}" for k, v in sorted(r["maintenance"].items()))]  # type: ignore[attr-defined]
        for r in figures.robots(session, window, rows, now)]


def _safe_cell(value: object) -> object:
    """A cell a spreadsheet will not run as a formula (a username such as =HYPERLINK(...))."""
    return f"'{value}" if isinstance(value, str) and value[:1] in ("=", "+", "-", "@", "\t", "\r") else value


@blueprint.get("/api/analytics/<report>.csv")
@login_required
@described(query=QUERY, answers={200: file_answer("text/csv", "one figure of the usage page as CSV")})
def report_csv(report: str) -> ResponseReturnValue:
    """One figure as CSV: sessions, students (time on robots), heatmap (minutes per weekday and hour), waits (every
    turn granted), robots (uptime and faults)."""
    name = schemas.report(report)
    found, window = _request_scope()
    out = io.StringIO()
    writer = csv.writer(out)
    for row in _csv_rows(name, found, window):
        writer.writerow([_safe_cell(cell) for cell in row])
    label = found.course.code if found.course else "all"
    filename = f"telelab-{name}-{label}-{window.first.isoformat()}-{window.last.isoformat()}.csv"
    return Response(out.getvalue(), mimetype="text/csv", headers={
        "Content-Disposition": f'attachment; filename="{_ascii(filename)}"', "Cache-Control": "no-store"})


def _ascii(name: str) -> str:
    return "".join(c if c.isascii() and (c.isalnum() or c in "-_.") else "_" for c in name)


@blueprint.get("/api/analytics/courses/<int:course_id>/xapi")
@login_required
@described(query={k: v for k, v in QUERY.items() if k != "course_id"},
           answers={200: file_answer("application/json", "the course's xAPI 1.0.3 statements", schema=obj(
               ("version", "course_id", "window", "statements"), version=one_of("1.0.3"), course_id=whole(0),
               window=obj_of(("from", "to", "utc_offset_min", "start", "end"),
                             {"utc_offset_min": whole(), "from": STRING, "to": STRING, "start": STRING, "end": STRING}),
               statements=array(OBJECT)))})
def course_statements(course_id: int) -> ResponseReturnValue:
    """The course's xAPI 1.0.3 statements for the window (lessons watched, tours followed, tests and exercises
    submitted, robot sessions held by its students), as a JSON document {"version", "statements"}."""
    found = scope.resolve(get_session(), _user(), course_id)
    window = schemas.window(request.args, (_now() + timedelta(minutes=_offset_guess())).date())
    homepage = analytics_of(current_app).sender.settings.homepage or request.url_root
    statements = StatementBuilder(get_session(), homepage).all(found.student_ids or (), window.start,
                                                               min(window.end, _now()), course_id)
    body = json.dumps({"version": "1.0.3", "course_id": course_id, "window": window.to_dict(),
                       "statements": statements}, indent=1)
    assert found.course is not None
    filename = _ascii(f"telelab-xapi-{found.course.code}-{window.first.isoformat()}-{window.last.isoformat()}.json")
    return Response(body, mimetype="application/json", headers={
        "Content-Disposition": f'attachment; filename="{filename}"', "Cache-Control": "no-store"})
