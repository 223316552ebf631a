"""Booking pages (week calendar, my bookings, iCalendar export) and the JSON API. Rules live in services."""

from __future__ import annotations

import os
from datetime import UTC, date, datetime, time, timedelta
from urllib.parse import urlencode

from flask import Blueprint, Response, abort, current_app, flash, jsonify, redirect, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.api.contract import OBJECT, STRING, about, array, described, obj, text
from middleware.bookings import ical, services
from middleware.bookings.availability import viewer_availability
from middleware.bookings.schemas import (
    MAX_BOOKING,
    SLOT_MINUTES,
    parse_booking_request,
    parse_instant,
    parse_time_zone,
    parse_week,
)
from middleware.bookings.week import form_default_start, week_days
from middleware.db import get_session
from middleware.errors import ApiError, flashed, unless_refused, written_date
from middleware.models import Booking
from middleware.robots.registry import RobotRegistry, robot_registry
from middleware.validation import within_calendar

blueprint = Blueprint("bookings", __name__)
blueprint.add_app_template_global(written_date, "written_date")  # a day and time in the page's language
DURATIONS_MIN = list(range(SLOT_MINUTES, int(MAX_BOOKING.total_seconds() // 60) + 1, SLOT_MINUTES))


@blueprint.record_once
def _configure(state) -> None:
    state.app.config.setdefault("BOOKING_GRACE_S", float(os.environ.get("TELELAB_BOOKING_GRACE_S", "600")))


def _now() -> datetime:
    return datetime.now(UTC)


def _require_robot(robot_name: str) -> str:
    if robot_name not in robot_registry().names():  # lab robots only: a practice robot is never booked
        raise ApiError(404, "unknown_robot", gettext("There is no robot named %(value)s.", value=repr(robot_name[:64])),
                                             "robot_name")
    return robot_name


# --- JSON API -----------------------------------------------------------------------------------


@blueprint.get("/api/bookings")
@login_required
@described(answers={200: obj(("bookings",), bookings=array(OBJECT))})
def api_my_bookings() -> ResponseReturnValue:
    """The current user's bookings that end in the last 30 days or later."""
    session, now = get_session(), _now()
    views = services.describe(session, current_user, services.user_bookings(session, current_user.id,
                                                                             now - timedelta(days=30)), now)
    return jsonify({"bookings": [v.to_dict() for v in views]})


@blueprint.post("/api/bookings")
@login_required
@described(
    body=obj(
        ("starts_at",),
        robot_name=about("a robot (or pool)"),
        pool=about("a pool's kind (or robot_name)"),
        starts_at=about("ISO 8601"),
        ends_at=about("ISO 8601 (or duration_min)"),
        duration_min=about("minutes"),
        kind=about("personal or course"),
        course_id=about("the course, for a course booking"),
    ),
    answers={201: obj(("booking",), booking=OBJECT)},
    refusals=(409,),
)
def api_create_booking() -> ResponseReturnValue:
    """Books a slot: {robot_name | pool, starts_at, ends_at | duration_min, kind?, course_id?}."""
    data = request.get_json(silent=True)
    if not isinstance(data, dict):
        raise ApiError(400, "invalid_field", gettext("Send the booking as a JSON object."), "body")
    session, now = get_session(), _now()
    booking_request = parse_booking_request(data)
    if booking_request.pool_kind is None:
        _require_robot(booking_request.robot_name)
    booking = services.create_booking(session, current_user, booking_request, now)
    return jsonify({"booking": services.describe(session, current_user, [booking], now)[0].to_dict()}), 201


@blueprint.delete("/api/bookings/<int:booking_id>")
@login_required
@described(answers={200: obj(("booking",), booking=OBJECT)}, refusals=(409,))
def api_cancel_booking(booking_id: int) -> ResponseReturnValue:
    """Cancels a booking (the booker, a tutor of its course, or an admin)."""
    session, now = get_session(), _now()
    booking = services.cancel_booking(session, current_user, booking_id, now)
    return jsonify({"booking": services.describe(session, current_user, [booking], now)[0].to_dict()})


@blueprint.get("/api/robots/<robot_name>/bookings")
@login_required
@described(
    query={
        "from": text(64, description="ISO 8601"),
        "to": text(64, description="ISO 8601, at most 62 days after from"),
    },
    answers={200: obj(("robot_name", "from"), robot_name=STRING, bookings=array(OBJECT))},
)
def api_robot_bookings(robot_name: str) -> ResponseReturnValue:
    """The robot's bookings between ?from= and ?to= (ISO 8601; default: this ISO week in UTC)."""
    _require_robot(robot_name)
    now = _now()
    start, end = services.iso_week_bounds(now)
    if request.args.get("from"):
        start = parse_instant(request.args["from"], "from")
    if request.args.get("to"):
        end = parse_instant(request.args["to"], "to")
    if end <= start or end - start > timedelta(days=62):
        raise ApiError(400, "invalid_field", gettext("to must be after from, at most 62 days later."), "to")
    session = get_session()
    views = services.describe(session, current_user, services.robot_bookings(session, robot_name, start, end), now)
    return jsonify({"robot_name": robot_name, "from": start.strftime("%Y-%m-%dT%H:%M:%SZ"),
                    "to": end.strftime("%Y-%m-%dT%H:%M:%SZ"), "bookings": [v.to_dict() for v in views]})


# --- pages ----------------------------------------------------------------------------------------


MAX_PAGE_ARGUMENT = 64  # a robot name, a date, a time zone name


def _page_url(robot_name: str | None, week: str | None, tz: str | None, hours: str | None = None) -> str:
    """The week page's address; values that no page would use (a form's hostile text) are left out, so a
    redirect never carries what the client sent in bulk."""
    args = {k: v for k, v in {"robot": robot_name, "week": week, "tz": tz, "hours": hours}.items()
            if v and len(v) <= MAX_PAGE_ARGUMENT}
    return url_for("bookings.page") + ("?" + urlencode(args) if args else "")


@blueprint.get("/bookings")
@login_required
def page() -> ResponseReturnValue:
    """The week calendar of one robot, with the booking form and the user's own bookings."""
    registry = robot_registry()
    names = registry.names()
    robot_name = request.args.get("robot") or (names[0] if names else None)
    if robot_name is not None and robot_name not in names:
        abort(404)
    zone = parse_time_zone(request.args.get("tz"))
    now = _now()
    monday = parse_week(request.args.get("week"), zone, now)
    all_hours = request.args.get("hours") == "all"
    session = get_session()
    days = []
    if robot_name is not None:
        start = datetime.combine(monday, time(0), tzinfo=zone).astimezone(UTC)
        views = services.describe(session, current_user, services.robot_bookings(
            session, robot_name, start - timedelta(days=1), start + timedelta(days=8)), now)
        days = week_days(monday, zone, views, now, all_hours)
    mine = [v for v in services.describe(session, current_user,
                                         services.user_bookings(session, current_user.id, now), now)
            if v.status in ("booked", "checked_in")]
    allowance = None
    if current_user.role == "student":
        minutes, _course = services.student_allowance(session, current_user.id)
        allowance = {"week_min": minutes, "used_min": services.minutes_booked_in_week(session, current_user.id, now)}
    tz_name = str(zone.key)
    week_iso = monday.isoformat()
    availability = viewer_availability(days)
    return render_template(
        "bookings/week.html", robots=[(n, registry.addresses[n].title) for n in names], robot_name=robot_name,
        robot_title=registry.addresses[robot_name].title if robot_name else None, days=availability.days,
        availability=availability, mine=mine,
        zone=zone, tz_name=tz_name, week=week_iso, all_hours=all_hours, durations=DURATIONS_MIN,
        courses=services.tutored_courses(session, current_user), allowance=allowance,
        times=[f"{h:02d}:{m:02d}" for h in range(24) for m in (0, 30)],
        suggested_start=form_default_start(monday, zone, now),
        prev_url=_page_url(robot_name, (monday - timedelta(days=7)).isoformat(), tz_name, "all" if all_hours else None),
        next_url=_page_url(robot_name, (monday + timedelta(days=7)).isoformat(), tz_name, "all" if all_hours else None),
        this_week_url=_page_url(robot_name, None, tz_name, "all" if all_hours else None),
        hours_url=_page_url(robot_name, week_iso, tz_name, None if all_hours else "all"),
        robot_urls={n: _page_url(n, week_iso, tz_name) for n in names},
        pool=_pool_of(registry, robot_name),
    )


def _pool_of(registry: RobotRegistry, robot_name: str | None) -> dict[str, object] | None:
    """The kind of robot_name and how many robots share it, when it has others (a pool booking may be offered)."""
    if robot_name is None:
        return None
    kind = registry.addresses[robot_name].kind
    count = sum(1 for n in registry.names() if registry.addresses[n].kind == kind)
    return {"kind": kind, "count": count} if kind and count > 1 else None


def _form_starts_at(form: dict[str, str]) -> str | None:
    """starts_at from a slot button, or from the date and time fields read in the form's time zone."""
    if form.get("starts_at"):
        return form["starts_at"]
    try:
        day = date.fromisoformat(form.get("date", ""))
        hour, minute = (int(part) for part in form.get("time", "").split(":"))
        local = datetime.combine(day, time(hour, minute), tzinfo=parse_time_zone(form.get("tz")))
    except ValueError:
        return None
    if not within_calendar(local):
        return None
    return local.astimezone(UTC).isoformat()


@blueprint.post("/bookings")
@login_required
def create_from_form() -> ResponseReturnValue:
    """The booking form: books, then shows the week again with a sentence saying what happened."""
    form = request.form.to_dict()
    back = _page_url(form.get("robot_name"), form.get("week"), form.get("tz"))
    form["starts_at"] = _form_starts_at(form) or ""
    if not form["starts_at"]:
        flash(gettext("Choose a free slot, or a date and a time, to book."), "error")
        return redirect(back, 303)

    def book() -> ResponseReturnValue:
        booking_request = parse_booking_request(form)
        if booking_request.pool_kind is None:
            _require_robot(booking_request.robot_name)
        booking = services.create_booking(get_session(), current_user, booking_request, _now())
        zone = parse_time_zone(form.get("tz"))
        what = booking.robot_name or gettext("any %(kind)s robot (assigned when the slot starts)",
                                             kind=booking.pool_kind)
        starts, ends = booking_request.starts_at.astimezone(zone), booking_request.ends_at.astimezone(zone)
        flash(gettext("Booked %(what)s on %(starts)s–%(ends)s.", what=what,
                      starts=written_date(starts, "%a %d %b, %H:%M", "EEE dd MMM, HH:mm"),
                      ends=written_date(ends, "%H:%M", "HH:mm")), "success")
        return redirect(back, 303)

    # Every refusal is the form's, an unknown robot or someone else's booking too: the week shows the sentence.
    return unless_refused(book, flashed(back), about_the_page=())



@blueprint.post("/bookings/<int:booking_id>/cancel")
@login_required
def cancel_from_form(booking_id: int) -> ResponseReturnValue:
    """The cancel button of a booking."""
    back = _page_url(request.form.get("robot_name"), request.form.get("week"), request.form.get("tz"))

    def cancel() -> ResponseReturnValue:
        services.cancel_booking(get_session(), current_user, booking_id, _now())
        flash(gettext("Booking cancelled; the slot is free again."), "success")
        return redirect(back, 303)

    return unless_refused(cancel, flashed(back), about_the_page=())


@blueprint.get("/bookings.ics")
@login_required
def ical_export() -> ResponseReturnValue:
    """The user's bookings (and their courses' class sessions) as an iCalendar file."""
    session, now = get_session(), _now()
    since = now - timedelta(days=30)
    bookings: list[Booking] = services.user_bookings(session, current_user.id, since)
    bookings += services.class_sessions_for_student(session, current_user.id, since)
    registry = robot_registry()
    views = services.describe(session, current_user, bookings, now)
    host = request.host.split(":")[0] or "telelab"
    grace_min = services.grace_period_s(current_app.config.get("BOOKING_GRACE_S")) / 60
    events = []
    for view in sorted(views, key=lambda v: v.starts_at):
        address = registry.addresses.get(view.robot_name) if view.robot_name else None
        title = address.title if address else (view.robot_name or f"any {view.pool_kind} robot")
        opens = (url_for("lab.console", robot_name=view.robot_name, _external=True) if view.robot_name
                 else url_for("pools.wait_page", kind=view.pool_kind, _external=True))
        summary = (f"Telelab class session ({view.course_code}) on {title}" if view.kind == "class"
                   else f"Telelab booking: {title}")
        events.append(ical.CalendarEvent(
            uid=f"booking-{view.id}@{host}", starts_at=view.starts_at, ends_at=view.ends_at, summary=summary,
            description=f"Robot {title}. Open {opens} within {grace_min:g} minutes of the start, "
                        "or the slot goes back to the queue.",
            status="CANCELLED" if view.status in ("cancelled", "released") else "CONFIRMED"))
    body = ical.calendar(events, f"Telelab bookings of {current_user.username}", now)
    return Response(body, mimetype="text/calendar", headers={
        "Content-Disposition": 'attachment; filename="telelab-bookings.ics"', "Cache-Control": "no-store"})
