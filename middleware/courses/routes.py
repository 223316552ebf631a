"""Course pages and API: list and create courses, settings, members, enrolment by name and by CSV file."""

from __future__ import annotations

import base64
from collections.abc import Callable
from typing import Any

from flask import Blueprint, Response, flash, jsonify, redirect, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required
from sqlalchemy.orm import Session

from middleware.accounts.invitations import list_invitations
from middleware.accounts.services import forbidden
from middleware.api.contract import ID, OBJECT, STRING, Answer, about, array, described, obj, one_of, whole
from middleware.auth.schemas import InvalidField
from middleware.courses import services
from middleware.courses.schemas import (
    ALLOWANCE_MIN,
    TURN_LENGTH_S,
    parse_settings,
    report_csv,
)
from middleware.db import get_session
from middleware.errors import unless_refused
from middleware.models import Role
from middleware.web import json_body, now

blueprint = Blueprint("courses", __name__)


def _require_teacher() -> None:
    if current_user.role not in (Role.TUTOR, Role.ADMIN):
        raise forbidden(gettext("Only tutors and admins manage courses."))


def _page(template: str, status: int = 200, **context: Any) -> tuple[str, int]:
    return render_template(template, turn_bounds=TURN_LENGTH_S, allowance_bounds=ALLOWANCE_MIN, **context), status


# --- pages ----------------------------------------------------------------------------------------


def _index(errors: dict[str, str] | None = None, form: dict[str, str] | None = None,
           status: int = 200) -> ResponseReturnValue:
    _require_teacher()
    return _page("courses/index.html", status, courses=services.list_courses(get_session(), current_user),
                 errors=errors or {}, form=form or {})


@blueprint.get("/courses")
@login_required
def index() -> ResponseReturnValue:
    """The courses the tutor teaches (every course for an admin) and the form to create one."""
    return _index()


@blueprint.post("/courses")
@login_required
def create() -> ResponseReturnValue:
    """Creates a course and opens it."""
    form = request.form.to_dict()

    def create() -> ResponseReturnValue:
        _require_teacher()
        settings = parse_settings({k: form.get(k) for k in ("turn_length_s", "booking_allowance_min",
                                                         "graded_run_hold_min")})
        course = services.create_course(get_session(), current_user, form.get("code"), form.get("title"), settings)
        flash(gettext("Course %(code)s created. Enrol students or invite them below.", code=course.code), "success")
        return redirect(url_for("courses.detail", course_id=course.id), 303)

    return unless_refused(create, lambda refused: _index({refused.field or "code": refused.message}, form,
                                                         refused.status))


def _detail(course_id: int, status: int = 200, errors: dict[str, str] | None = None,
            form: dict[str, str] | None = None,
            report: services.EnrolmentReport | None = None) -> ResponseReturnValue:
    dbs = get_session()
    course = services.managed_course(dbs, current_user, course_id)
    report_href = None
    if report is not None:
        data = report_csv(report.enrolled, report.created, report.refused).encode()
        report_href = "data:text/csv;charset=utf-8;base64," + base64.b64encode(data).decode()
    response = _page("courses/detail.html", status, course=services.describe(dbs, current_user, course),
                     members=services.members(dbs, current_user, course_id), errors=errors or {},
                     form=form or {}, report=report, report_href=report_href,
                     invitations=list_invitations(dbs, current_user, course_id, now())[:20])
    if report is not None:
        return response[0], response[1], {"Cache-Control": "no-store"}
    return response


@blueprint.get("/courses/<int:course_id>")
@login_required
def detail(course_id: int) -> ResponseReturnValue:
    """One course: settings, members, enrolment, CSV upload and invitations (its tutors, admins)."""
    return _detail(course_id)


def _course_form(course_id: int, action: Callable[[Session, dict[str, str]], object],
                 success: str, about_the_page: tuple[int, ...] = (403, 404)) -> ResponseReturnValue:
    form = request.form.to_dict()

    def act() -> ResponseReturnValue:
        action(get_session(), form)
        flash(success, "success")
        return redirect(url_for("courses.detail", course_id=course_id), 303)

    return unless_refused(act, lambda refused: _detail(course_id, refused.status,
                                                       {refused.field or "form": refused.message}, form),
                          about_the_page)


@blueprint.post("/courses/<int:course_id>/settings")
@login_required
def settings(course_id: int) -> ResponseReturnValue:
    """Saves the title, turn length, booking allowance and graded run hold."""
    return _course_form(course_id, lambda dbs, form: services.update_settings(
        dbs, current_user, course_id, parse_settings(form)), gettext("Course settings saved."))


@blueprint.post("/courses/<int:course_id>/members")
@login_required
def enrol(course_id: int) -> ResponseReturnValue:
    """Enrols one existing student by username."""
    name = request.form.get("username", "").strip().lower()
    # A mistyped username (404) is the form's error; a course that is not there still fails in _detail.
    return _course_form(course_id, lambda dbs, form: services.enrol(dbs, current_user, course_id, form.get("username")),
                        gettext("%(name)s enrolled.", name=name), about_the_page=())


@blueprint.post("/courses/<int:course_id>/members/<int:user_id>/remove")
@login_required
def unenrol(course_id: int, user_id: int) -> ResponseReturnValue:
    """Removes a student from the course."""
    return _course_form(course_id, lambda dbs, _form: services.unenrol(dbs, current_user, course_id, user_id),
                        gettext("Student removed from the course."))


def _uploaded_bytes() -> bytes:
    upload = request.files.get("file")
    if upload is None or not upload.filename:
        raise InvalidField("file", gettext("Choose a CSV file to upload."))
    return upload.read()


@blueprint.post("/courses/<int:course_id>/members.csv")
@login_required
def enrol_csv(course_id: int) -> ResponseReturnValue:
    """Enrols (and creates accounts for) the usernames in an uploaded CSV file; shows the report once."""
    def enrol() -> ResponseReturnValue:
        return _detail(course_id, report=_enrol_uploaded_csv(course_id))

    return unless_refused(enrol, lambda refused: _detail(course_id, refused.status, {"file": refused.message}))


def _enrol_uploaded_csv(course_id: int) -> services.EnrolmentReport:
    dbs = get_session()
    services.managed_course(dbs, current_user, course_id)  # who may, before what was sent
    return services.enrol_from_csv(dbs, current_user, course_id, _uploaded_bytes())


# --- JSON API -----------------------------------------------------------------------------------


def _api(action: Callable[[Session], object], status: int = 200) -> ResponseReturnValue:
    return jsonify(action(get_session())), status


@blueprint.get("/api/courses")
@login_required
@described(answers={200: obj(("courses",), courses=array(OBJECT))})
def api_courses() -> ResponseReturnValue:
    """The courses the user belongs to (every course for an admin)."""
    return _api(lambda dbs: {"courses": [c.to_dict() for c in services.list_courses(dbs, current_user)]})


@blueprint.post("/api/courses")
@login_required
@described(
    body=obj(
        ("code", "title"),
        code=about("the course's code"),
        title=about("its title"),
        turn_length_s=about("seconds"),
        booking_allowance_min=about("minutes"),
        graded_run_hold_min=about("minutes"),
    ),
    answers={201: obj(("course",), course=OBJECT)},
    refusals=(409,),
)
def api_create_course() -> ResponseReturnValue:
    """{code, title, turn_length_s?, booking_allowance_min?, graded_run_hold_min?}: creates a course."""
    data = json_body()

    def action(dbs: Session) -> dict[str, object]:
        parsed = parse_settings({k: data.get(k) for k in ("turn_length_s", "booking_allowance_min",
                                                           "graded_run_hold_min")})
        course = services.create_course(dbs, current_user, data.get("code"), data.get("title"), parsed)
        return {"course": services.describe(dbs, current_user, course).to_dict()}

    return _api(action, 201)


@blueprint.get("/api/courses/<int:course_id>")
@login_required
@described(answers={200: obj(("course",), course=OBJECT)})
def api_course(course_id: int) -> ResponseReturnValue:
    """A course with its members (its tutors, admins)."""
    def action(dbs: Session) -> dict[str, object]:
        course = services.managed_course(dbs, current_user, course_id)
        return {"course": services.describe(dbs, current_user, course).to_dict(),
                "members": [m.to_dict() for m in services.members(dbs, current_user, course_id)]}

    return _api(action)


@blueprint.patch("/api/courses/<int:course_id>")
@login_required
@described(
    body=obj(title=about("its title"), turn_length_s=about("seconds"), booking_allowance_min=about("minutes")),
    answers={200: obj(("course",), course=OBJECT)},
)
def api_update_course(course_id: int) -> ResponseReturnValue:
    """{title?, turn_length_s?, booking_allowance_min?}: changes a course (its tutors, admins)."""
    data = json_body()

    def action(dbs: Session) -> dict[str, object]:
        services.managed_course(dbs, current_user, course_id)
        course = services.update_settings(dbs, current_user, course_id, parse_settings(data))
        return {"course": services.describe(dbs, current_user, course).to_dict()}

    return _api(action)


@blueprint.post("/api/courses/<int:course_id>/members")
@login_required
@described(
    body=obj(("username",), username=about("an existing student's username")),
    answers={201: obj(("enrolled",), enrolled=STRING), 200: obj(("enrolled",), enrolled=STRING)},
    refusals=(409,),
)
def api_enrol(course_id: int) -> ResponseReturnValue:
    """{username}: enrols an existing student account."""
    data = json_body()
    return _api(lambda dbs: {"enrolled": services.enrol(dbs, current_user, course_id, data.get("username")).username},
                201)


@blueprint.delete("/api/courses/<int:course_id>/members/<int:user_id>")
@login_required
@described(answers={200: obj(("removed",), removed=ID)})
def api_unenrol(course_id: int, user_id: int) -> ResponseReturnValue:
    """Removes a student from the course."""
    def action(dbs: Session) -> dict[str, object]:
        services.unenrol(dbs, current_user, course_id, user_id)
        return {"removed": user_id}

    return _api(action)


@blueprint.post("/api/courses/<int:course_id>/members.csv")
@login_required
@described(
    form=obj(("file",), file={"type": "string", "format": "binary", "description": "a CSV of usernames"}),
    query={"format": one_of("json", "csv")},
    answers={200: Answer(obj(("enrolled", "created", "refused"), description="services.EnrolmentReport",
                             enrolled=array(STRING),
                             created=array(obj(("username", "password"), username=STRING, password=STRING)),
                             refused=array(obj(("line", "value", "reason"), line=whole(), value=STRING,
                                               reason=STRING))),
                         description="the enrolment report (as CSV with ?format=csv)",
                         alternatives={"text/csv": STRING})},
    refusals=(413,),
)
def api_enrol_csv(course_id: int) -> ResponseReturnValue:
    """A CSV file (multipart field 'file'): the enrolment report as JSON, or as CSV with ?format=csv."""
    report = _enrol_uploaded_csv(course_id)
    if request.args.get("format") == "csv":
        return Response(report_csv(report.enrolled, report.created, report.refused), mimetype="text/csv",
                        headers={"Content-Disposition": 'attachment; filename="enrolment-report.csv"',
                                 "Cache-Control": "no-store"})
    return jsonify(report.to_dict()), 200, {"Cache-Control": "no-store"}

