"""LTI pages: the OIDC login and the launch (called by the LMS), the tool's JWKS, the deep-linking picker, the
admin's platform registrations and keys, and the tutor's roster sync and grade retries on the course page."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any
from urllib.parse import urlencode

from flask import Blueprint, current_app, flash, jsonify, redirect, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware import i18n
from middleware.accounts.services import require_admin
from middleware.auth import sessions
from middleware.db import get_session
from middleware.errors import Refused, flashed, unless_refused, written_number
from middleware.extensions import csrf
from middleware.lti import catalog, flow, grades, keys, launches, platforms, roster
from middleware.lti.accept import accept_launch, deep_link_owner, link_new_context
from middleware.robots.registry import robot_registry

blueprint = Blueprint("lti", __name__)
_LOGIN_PARAMS = ("iss", "login_hint", "target_link_uri", "lti_message_hint", "lti_deployment_id", "client_id")


def _login_params() -> dict[str, str]:
    return {k: request.values[k][:2000] for k in _LOGIN_PARAMS if isinstance(request.values.get(k), str)}


@blueprint.route("/lti/login", methods=["GET", "POST"])
@csrf.exempt
def login() -> ResponseReturnValue:
    """OIDC login initiation: first a check that this browser keeps cookies here (inside the LMS's frame it may
    not: then "Open in a new window"), then the redirect to the LMS's authorization endpoint."""
    params = _login_params()
    if not request.values.get("telelab_checked") and not request.values.get("lti1p3_new_window"):
        here = url_for("lti.login") + "?"
        return render_template("lti/login_check.html",
                               continue_url=here + urlencode({"telelab_checked": "1", **params}),
                               new_window_url=here + urlencode({"lti1p3_new_window": "1", **params}))
    return flow.login_redirect(get_session(), url_for("lti.launch", _external=True), params)


@blueprint.post("/lti/launch")
@csrf.exempt
def launch() -> ResponseReturnValue:
    """The launch (the LMS posts the signed id token): every check, then the person is signed in and sent to
    the placed page, or, for a deep-linking request, shown the picker."""
    def accept() -> ResponseReturnValue:
        dbs = get_session()
        validated = flow.validate_launch(dbs)
        accepted = accept_launch(dbs, validated, str(current_app.config["SECRET_KEY"]))
        sessions.begin(accepted.user)
        presentation = validated.claims.get(launches.PRESENTATION_CLAIM)
        locale = presentation.get("locale") if isinstance(presentation, dict) else validated.claims.get("locale")
        if isinstance(locale, str):
            i18n.remember_launch_locale(locale)  # the language of the pages, unless the person chose one
        if accepted.choose_course:
            return _link_page(validated.launch_id, validated.claims)
        if validated.is_deep_link:
            return _picker(validated.launch_id)
        return redirect(catalog.destination(accepted.target, accepted.course_id, accepted.teaches), 303)

    # A refused launch: its own page (what happened, what to do), nothing it did kept.
    return unless_refused(accept, lambda refused: (render_template("lti/refused.html", refused=refused),
                                                   refused.status), about_the_page=())


def _link_page(launch_id: str, claims: Mapping[str, Any], error: str | None = None,
               status: int = 200) -> ResponseReturnValue:
    context = claims.get(launches.CONTEXT_CLAIM)
    title = str((context.get("title") or context.get("label") or "") if isinstance(context, dict) else "")[:200]
    return render_template("lti/link_course.html", launch_id=launch_id, lms_course=title, error=error,
                           courses=launches.linkable_courses(get_session(), current_user)), status


@blueprint.post("/lti/link-course")
@login_required
def link_course() -> ResponseReturnValue:
    """An instructor's first launch from a new LMS course: links it to the chosen course (or a new one), then goes
    on where the launch was going."""
    dbs = get_session()
    launch_id = request.form.get("launch_id", "")[:200]
    restored = flow.restore_launch(dbs, launch_id)
    claims = restored.get_launch_data()

    def link() -> ResponseReturnValue:
        accepted = link_new_context(dbs, claims, flow.launch_platform(dbs, restored), current_user,
                                    request.form.get("course", "")[:20], str(current_app.config["SECRET_KEY"]))
        if restored.is_deep_link_launch():
            return _picker(launch_id)
        return redirect(catalog.destination(accepted.target, accepted.course_id, accepted.teaches), 303)

    return unless_refused(link, lambda refused: _link_page(launch_id, claims, refused.message, refused.status))


def _placeable(launch_id: str) -> list[catalog.Placeable]:
    """What the tutor may place in the LMS course of the deep-linking launch launch_id."""
    dbs = get_session()
    course_id = launches.context_course(dbs, dict(flow.restore_launch(dbs, launch_id).get_launch_data()))
    return catalog.placeable(dbs, current_user, robot_registry(current_app).names(), course_id)


def _picker(launch_id: str, error: str | None = None, status: int = 200) -> ResponseReturnValue:
    items = _placeable(launch_id)
    return render_template("lti/deep_link.html", items=items, launch_id=launch_id, error=error), status


@blueprint.post("/lti/deep-link")
@login_required
def deep_link() -> ResponseReturnValue:
    """Answers the LMS's deep-linking request with the chosen items, signed with the tool's key."""
    dbs = get_session()
    launch_id = request.form.get("launch_id", "")[:200]
    restored = flow.restore_launch(dbs, launch_id)
    deep_link_owner(dbs, restored.get_launch_data(), current_user)
    chosen = request.form.getlist("target")[:50]
    if not chosen:
        return _picker(launch_id, gettext("Choose at least one item to place in the LMS course."), 400)
    known = {item.target: item for item in _placeable(launch_id)}
    if any(target not in known for target in chosen):
        return _picker(launch_id, gettext("One of the chosen items is not offered any more. Choose again."), 400)
    launch_url = url_for("lti.launch", _external=True)
    items = [(known[t].title[:200], launch_url, t, known[t].score_maximum) for t in chosen]
    return_url, token = flow.deep_link_response(restored, items, str(current_app.config["SECRET_KEY"]))
    return render_template("lti/deep_link_return.html", return_url=return_url, token=token, items=items)


@blueprint.get("/lti/jwks.json")
def jwks() -> ResponseReturnValue:
    """The tool's public keys (every unretired one)."""
    response = jsonify(keys.jwks(get_session()))
    response.headers["Cache-Control"] = "public, max-age=300"
    return response


def _admin_page(errors: dict[str, str] | None = None, form: dict[str, Any] | None = None,
                status: int = 200) -> ResponseReturnValue:
    require_admin(current_user)
    dbs = get_session()
    keys.signing_key(dbs)
    return render_template("lti/admin.html", platforms=platforms.listed(dbs), keys=keys.live_keys(dbs),
                           urls=platforms.tool_urls(request.host_url), errors=errors or {}, form=form or {},
                           pending=grades.pending_count(dbs)), status


@blueprint.get("/admin/lti")
@login_required
def admin_page() -> ResponseReturnValue:
    """Registered platforms, what an LMS's administrator pastes, the tool's keys (admins)."""
    return _admin_page()


@blueprint.post("/admin/lti/platforms")
@login_required
def admin_register() -> ResponseReturnValue:
    """Registers (or updates) a platform."""
    def register() -> ResponseReturnValue:
        require_admin(current_user)
        platform = platforms.register(get_session(), request.form.to_dict())
        flash(gettext("Registered %(name)s. Its launches are accepted from now on.", name=platform.name), "success")
        return redirect(url_for("lti.admin_page"), 303)

    return unless_refused(register, lambda refused: _admin_page({refused.field or "form": refused.message},
                                                                request.form.to_dict(), refused.status))


@blueprint.post("/admin/lti/platforms/<int:platform_id>/delete")
@login_required
def admin_remove(platform_id: int) -> ResponseReturnValue:
    """Removes a platform registration."""
    require_admin(current_user)
    platforms.remove(get_session(), platform_id)
    flash(gettext("The platform was removed: its launches are refused from now on."), "success")
    return redirect(url_for("lti.admin_page"), 303)


@blueprint.post("/admin/lti/keys/rotate")
@login_required
def admin_rotate() -> ResponseReturnValue:
    """A new signing key; the old one stays published until retired."""
    require_admin(current_user)
    key = keys.rotate(get_session())
    flash(gettext("New signing key %(kid)s… The previous key stays in the key set until you retire it.",
                  kid=key.kid[:12]), "success")
    return redirect(url_for("lti.admin_page"), 303)


@blueprint.post("/admin/lti/keys/<kid>/retire")
@login_required
def admin_retire(kid: str) -> ResponseReturnValue:
    """Takes an old key out of the key set."""
    def retire() -> ResponseReturnValue:
        require_admin(current_user)
        keys.retire(get_session(), kid[:64])
        flash(gettext("The key was retired: platforms no longer find it in the key set."), "success")
        return redirect(url_for("lti.admin_page"), 303)

    return unless_refused(retire, flashed(url_for("lti.admin_page")))


@blueprint.post("/courses/<int:course_id>/lti/roster")
@login_required
def roster_sync(course_id: int) -> ResponseReturnValue:
    """Syncs the course's roster from the LMS (its tutors)."""
    def sync() -> ResponseReturnValue:
        report = roster.sync(get_session(), current_user, course_id)
        flash(report.sentence(), "success")
        return redirect(url_for("courses.detail", course_id=course_id), 303)

    return unless_refused(sync, flashed(url_for("courses.detail", course_id=course_id)), about_the_page=(403, 404))


@blueprint.post("/courses/<int:course_id>/lti/grades/retry")
@login_required
def grades_retry(course_id: int) -> ResponseReturnValue:
    """Sends the course's waiting grades now (its tutors)."""
    dbs = get_session()
    if not roster.teaches_course(dbs, current_user, course_id):
        raise Refused(403, "forbidden", gettext("Only the course's tutors send its grades."))
    count = grades.retry_now(dbs, course_id)
    flash(gettext("Grades waiting for the LMS, sent again now: %(count)s.", count=written_number(count)), "success")
    return redirect(url_for("courses.detail", course_id=course_id), 303)
