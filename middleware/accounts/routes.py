"""Account pages and API: admin account and robot management, password change and reset, invitations.

Routes parse and respond; the rules (who may do what) are in services.py, invitations.py and
robot_admin.py, which raise Refused or InvalidField.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from datetime import UTC, datetime
from typing import Any

from flask import Blueprint, abort, flash, jsonify, redirect, render_template, request, url_for
from flask_login import current_user, login_required, logout_user

from middleware.accounts import invitations, robot_admin, services
from middleware.accounts.schemas import clean_flag, clean_id, clean_invitation_days, clean_optional_id
from middleware.accounts.services import Refused
from middleware.auth import sessions
from middleware.auth.routes import safe_next_url
from middleware.auth.schemas import InvalidField
from middleware.auth.services import change_own_password
from middleware.courses.services import list_courses
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.robots.registry import robot_registry

blueprint = Blueprint("accounts", __name__)


def _now() -> datetime:
    return datetime.now(UTC)


def api_error(error: Refused | InvalidField) -> ApiError:
    """The JSON error for a refusal or an invalid field."""
    if isinstance(error, InvalidField):
        return ApiError(400, "invalid_field", error.message, error.field)
    return ApiError(error.status, error.code, error.message, error.field)


def page_refusal(error: Refused) -> None:
    """Aborts with the refusal's status when it is not about a field the form can show (403, 404)."""
    if error.status in (403, 404):
        get_session().rollback()
        abort(error.status)


def refusals_as_pages(view: Callable[..., Any]) -> Callable[..., Any]:
    """A page view whose Refused about the page itself (403, 404) becomes that error page."""
    @functools.wraps(view)
    def page(*args: Any, **kwargs: Any) -> Any:
        try:
            return view(*args, **kwargs)
        except Refused as refused:
            page_refusal(refused)
            raise
    return page


def _back_url() -> str:
    """The form's "back" page when it is a path on this site, else the lab's index."""
    return safe_next_url(request.form.get("back")) or url_for("lab.index")


def _json_body() -> dict[str, object]:
    data = request.get_json(silent=True)
    if not isinstance(data, dict):
        raise ApiError(400, "invalid_field", "Send a JSON object.", "body")
    return data


# --- own password ---------------------------------------------------------------------------------


@blueprint.get("/account/password")
@login_required
def password_page():  # type: ignore[no-untyped-def]
    """The form to change one's own password."""
    return render_template("accounts/password.html", errors={})


@blueprint.post("/account/password")
@login_required
def password_submit():  # type: ignore[no-untyped-def]
    """Changes one's own password (the current one is required)."""
    dbs = get_session()
    new, again = request.form.get("new_password", ""), request.form.get("new_password_again", "")
    try:
        if new != again:
            raise InvalidField("new_password_again", "The two new passwords differ; type the same one twice.")
        change_own_password(dbs, current_user, request.form.get("current_password", ""), new)
    except InvalidField as invalid:
        dbs.rollback()
        field = "new_password" if invalid.field == "password" else invalid.field
        return render_template("accounts/password.html", errors={field: invalid.message}), 400
    dbs.commit()
    sessions.password_changed(current_user)
    flash("Your password has been changed.", "success")
    return redirect(url_for("lab.index"), 303)


@blueprint.post("/api/account/password")
@login_required
def api_password():  # type: ignore[no-untyped-def]
    """{current_password, new_password}: changes one's own password."""
    data, dbs = _json_body(), get_session()
    try:
        change_own_password(dbs, current_user, str(data.get("current_password") or ""), data.get("new_password"))  # type: ignore[arg-type]
    except InvalidField as invalid:
        dbs.rollback()
        raise api_error(InvalidField("new_password" if invalid.field == "password" else invalid.field,
                                     invalid.message)) from None
    dbs.commit()
    sessions.password_changed(current_user)
    return jsonify({"changed": True})


# --- accounts (admins) and password resets ---------------------------------------------------------


def _users_page(errors: dict[str, str] | None = None, form: dict[str, str] | None = None, status: int = 200):  # type: ignore[no-untyped-def]
    users = services.list_users(get_session(), current_user)
    return render_template("accounts/users.html", users=users, errors=errors or {}, form=form or {},
                           roles=["student", "tutor", "admin"]), status


@blueprint.get("/admin/users")
@login_required
@refusals_as_pages
def users_page():  # type: ignore[no-untyped-def]
    """Every account, with forms to create, disable or enable, re-role and reset (admins)."""
    return _users_page()


@blueprint.post("/admin/users")
@login_required
def users_create():  # type: ignore[no-untyped-def]
    """Creates an account and shows its generated password once."""
    dbs = get_session()
    try:
        user, password = services.create_account(dbs, current_user, request.form.get("username", ""),
                                                 request.form.get("role", ""))
    except Refused as refused:
        page_refusal(refused)
        dbs.rollback()
        return _users_page({refused.field or "username": refused.message}, request.form.to_dict(), refused.status)
    except InvalidField as invalid:
        dbs.rollback()
        return _users_page({invalid.field: invalid.message}, request.form.to_dict(), 400)
    dbs.commit()
    return _password_shown(user.username, password, created=True)


def _password_shown(username: str, password: str, created: bool = False):  # type: ignore[no-untyped-def]
    response = render_template("accounts/password_shown.html", username=username, password=password, created=created)
    return response, 200, {"Cache-Control": "no-store"}


def _admin_form_action(action):  # type: ignore[no-untyped-def]
    dbs = get_session()
    try:
        user = action(dbs)
    except Refused as refused:
        page_refusal(refused)
        dbs.rollback()
        flash(refused.message, "error")
        return redirect(url_for("accounts.users_page"), 303)
    except InvalidField as invalid:
        dbs.rollback()
        flash(invalid.message, "error")
        return redirect(url_for("accounts.users_page"), 303)
    dbs.commit()
    flash(f"{user.username}: {'active' if user.is_active else 'disabled'}, {user.role}.", "success")
    return redirect(url_for("accounts.users_page"), 303)


@blueprint.post("/admin/users/<int:user_id>/active")
@login_required
def users_set_active(user_id: int):  # type: ignore[no-untyped-def]
    """Disables (active=0) or enables (active=1) an account."""
    return _admin_form_action(lambda dbs: services.set_active(
        dbs, current_user, user_id, clean_flag(request.form.get("active", ""), "active")))


@blueprint.post("/admin/users/<int:user_id>/role")
@login_required
def users_set_role(user_id: int):  # type: ignore[no-untyped-def]
    """Changes an account's role."""
    return _admin_form_action(lambda dbs: services.change_role(dbs, current_user, user_id, request.form.get("role")))


@blueprint.post("/users/<int:user_id>/reset-password")
@login_required
def reset_password(user_id: int):  # type: ignore[no-untyped-def]
    """Gives an account a generated password and shows it once (admins; tutors for their students)."""
    dbs = get_session()
    try:
        user, password = services.reset_password(dbs, current_user, user_id)
    except Refused as refused:
        page_refusal(refused)
        dbs.rollback()
        flash(refused.message, "error")
        return redirect(request.referrer or url_for("lab.index"), 303)
    dbs.commit()
    return _password_shown(user.username, password)


@blueprint.get("/api/users")
@login_required
def api_users():  # type: ignore[no-untyped-def]
    """Every account (admins)."""
    try:
        return jsonify({"users": [u.to_dict() for u in services.list_users(get_session(), current_user)]})
    except Refused as refused:
        raise api_error(refused) from None


@blueprint.post("/api/users")
@login_required
def api_create_user():  # type: ignore[no-untyped-def]
    """{username, role}: creates an account; the answer holds the generated password, once."""
    data, dbs = _json_body(), get_session()
    try:
        user, password = services.create_account(dbs, current_user, data.get("username"), data.get("role"))
    except (Refused, InvalidField) as error:
        dbs.rollback()
        raise api_error(error) from None
    dbs.commit()
    body = services.UserView(user.id, user.username, user.role, user.is_active).to_dict()
    return jsonify({"user": body, "password": password}), 201, {"Cache-Control": "no-store"}


@blueprint.patch("/api/users/<int:user_id>")
@login_required
def api_update_user(user_id: int):  # type: ignore[no-untyped-def]
    """{role?, is_active?}: changes an account (admins)."""
    data, dbs = _json_body(), get_session()
    try:
        services.require_admin(current_user)
        user = services.get_user(dbs, user_id)
        if "role" in data:
            user = services.change_role(dbs, current_user, user_id, data["role"])
        if "is_active" in data:
            user = services.set_active(dbs, current_user, user_id, clean_flag(data["is_active"], "is_active"))
    except (Refused, InvalidField) as error:
        dbs.rollback()
        raise api_error(error) from None
    dbs.commit()
    return jsonify({"user": services.UserView(user.id, user.username, user.role, user.is_active).to_dict()})


@blueprint.post("/api/users/<int:user_id>/password-reset")
@login_required
def api_reset_password(user_id: int):  # type: ignore[no-untyped-def]
    """Gives an account a generated password, returned once (admins; tutors for their students)."""
    dbs = get_session()
    try:
        user, password = services.reset_password(dbs, current_user, user_id)
    except Refused as refused:
        dbs.rollback()
        raise api_error(refused) from None
    dbs.commit()
    return jsonify({"username": user.username, "password": password}), 200, {"Cache-Control": "no-store"}


# --- invitations ----------------------------------------------------------------------------------


@blueprint.get("/admin/invitations")
@login_required
@refusals_as_pages
def invitations_page():  # type: ignore[no-untyped-def]
    """Every invitation and the form to invite anyone (admins)."""
    views = invitations.list_invitations(get_session(), current_user, None, _now())
    return render_template("accounts/invitations.html", invitations=views, errors={},
                           courses=list_courses(get_session(), current_user))


@blueprint.post("/invitations")
@login_required
def invitations_create():  # type: ignore[no-untyped-def]
    """Creates an invitation (a tutor for their course, an admin for anyone) and shows its link once."""
    dbs = get_session()
    back = _back_url()
    try:
        course_id = clean_optional_id(request.form.get("course_id"), "course_id")
        invitation, token = invitations.create_invitation(
            dbs, current_user, request.form.get("role") or "student", course_id,
            clean_invitation_days(request.form.get("days")), _now())
    except Refused as refused:
        page_refusal(refused)
        dbs.rollback()
        flash(refused.message, "error")
        return redirect(back, 303)
    except InvalidField as invalid:
        dbs.rollback()
        flash(invalid.message, "error")
        return redirect(back, 303)
    dbs.commit()
    link = url_for("accounts.join", token=token, _external=True)
    return render_template("accounts/invitation_created.html", link=link, invitation=invitation,
                           back=back), 200, {"Cache-Control": "no-store"}


@blueprint.post("/api/invitations")
@login_required
def api_create_invitation():  # type: ignore[no-untyped-def]
    """{role, course_id?, days?}: an invitation link, returned once."""
    data, dbs = _json_body(), get_session()
    try:
        invitation, token = invitations.create_invitation(
            dbs, current_user, data.get("role") or "student", clean_optional_id(data.get("course_id"), "course_id"),
            clean_invitation_days(data.get("days")), _now())
    except (Refused, InvalidField) as error:
        dbs.rollback()
        raise api_error(error) from None
    dbs.commit()
    return jsonify({"id": invitation.id, "role": invitation.role, "course_id": invitation.course_id,
                    "expires_at": invitation.expires_at.isoformat(),
                    "url": url_for("accounts.join", token=token, _external=True)}), 201, {"Cache-Control": "no-store"}


@blueprint.post("/invitations/<int:invitation_id>/revoke")
@login_required
def invitations_revoke(invitation_id: int):  # type: ignore[no-untyped-def]
    """Withdraws a pending invitation from the page that lists it."""
    dbs = get_session()
    back = _back_url()
    try:
        invitations.revoke_invitation(dbs, current_user, invitation_id, _now())
    except Refused as refused:
        dbs.rollback()
        page_refusal(refused)
        flash(refused.message, "error")
        return redirect(back, 303)
    dbs.commit()
    flash("The invitation was withdrawn: its link no longer works.", "success")
    return redirect(back, 303)


@blueprint.delete("/api/invitations/<int:invitation_id>")
@login_required
def api_revoke_invitation(invitation_id: int):  # type: ignore[no-untyped-def]
    """Withdraws a pending invitation; answers it as lists show it."""
    dbs = get_session()
    try:
        view = invitations.revoke_invitation(dbs, current_user, invitation_id, _now())
    except Refused as refused:
        dbs.rollback()
        raise api_error(refused) from None
    dbs.commit()
    return jsonify({"invitation": view.to_dict()})


UNUSABLE = {
    "unknown": (404, "This invitation link is not valid",
                "The link is not one we issued. Check that you copied all of it, or ask your tutor for a new one."),
    "expired": (410, "This invitation has expired",
                "Invitation links last a few days. Ask your tutor or the lab's admin for a new one."),
    "used": (410, "This invitation has already been used",
             "Each link creates one account. If it was you, log in; otherwise ask for a new link."),
    "revoked": (410, "This invitation was withdrawn",
                "The person who invited you withdrew this link. Ask them for a new one if you still need an account."),
}


def _join_unusable(reason: str):  # type: ignore[no-untyped-def]
    status, title, message = UNUSABLE[reason]
    return render_template("accounts/join_invalid.html", title=title, message=message, reason=reason), status


@blueprint.get("/join/<token>")
def join(token: str):  # type: ignore[no-untyped-def]
    """The form that turns an invitation link into an account."""
    try:
        invitation, course = invitations.find_usable(get_session(), token, _now())
    except invitations.InvitationUnusable as unusable:
        return _join_unusable(unusable.reason)
    return render_template("accounts/join.html", invitation=invitation, course=course, token=token,
                           errors={}, username=""), 200, {"Cache-Control": "no-store"}


@blueprint.post("/join/<token>")
def join_submit(token: str):  # type: ignore[no-untyped-def]
    """Creates the account, enrols it, logs it in and opens the lab."""
    dbs = get_session()
    username = request.form.get("username", "")[:128]
    try:
        user = invitations.accept(dbs, token, username, request.form.get("password", "")[:300],
                                  request.form.get("password_again", "")[:300], _now())
    except invitations.InvitationUnusable as unusable:
        dbs.rollback()
        return _join_unusable(unusable.reason)
    except (Refused, InvalidField) as error:
        dbs.rollback()
        invitation, course = invitations.find_usable(dbs, token, _now())
        return render_template("accounts/join.html", invitation=invitation, course=course, token=token,
                               errors={error.field or "username": error.message}, username=username), 400
    dbs.commit()
    if current_user.is_authenticated:
        logout_user()
    sessions.begin(user)
    flash(f"Welcome, {user.username}. Your account is ready.", "success")
    return redirect(url_for("lab.index"), 303)


# --- robots (admins) ------------------------------------------------------------------------------


def _robots_page(errors: dict[str, str] | None = None, form: dict[str, str] | None = None, status: int = 200):  # type: ignore[no-untyped-def]
    registry = robot_registry()
    views = robot_admin.list_robots(get_session(), current_user)
    online = {v.name: (registry.get(v.name).is_online() if v.enabled and registry.get(v.name) else False)  # type: ignore[union-attr]
              for v in views}
    return render_template("accounts/robots.html", robots=views, online=online, errors=errors or {},
                           form=form or {}), status


@blueprint.get("/admin/robots")
@login_required
@refusals_as_pages
def robots_page():  # type: ignore[no-untyped-def]
    """The robots table with whether each answers, and forms to add and change robots (admins)."""
    return _robots_page()


@blueprint.post("/admin/robots")
@login_required
def robots_add():  # type: ignore[no-untyped-def]
    """Adds a robot."""
    dbs = get_session()
    form = request.form.to_dict()
    try:
        robot = robot_admin.add_robot(dbs, current_user, form.get("name"), form.get("title"), form.get("address"))
    except Refused as refused:
        page_refusal(refused)
        dbs.rollback()
        return _robots_page({refused.field or "name": refused.message}, form, refused.status)
    except InvalidField as invalid:
        dbs.rollback()
        return _robots_page({invalid.field: invalid.message}, form, 400)
    dbs.commit()
    robot_registry().refresh()
    flash(f"Robot {robot.name} added.", "success")
    return redirect(url_for("accounts.robots_page"), 303)


@blueprint.post("/admin/robots/<int:robot_id>")
@login_required
def robots_update(robot_id: int):  # type: ignore[no-untyped-def]
    """Changes a robot's title, address or enabled flag (only the fields sent)."""
    dbs = get_session()
    form = request.form
    try:
        robot = robot_admin.update_robot(
            dbs, current_user, robot_id, title=form.get("title"), address=form.get("address"),
            enabled=clean_flag(form["enabled"], "enabled") if "enabled" in form else None)
    except Refused as refused:
        page_refusal(refused)
        dbs.rollback()
        flash(refused.message, "error")
        return redirect(url_for("accounts.robots_page"), 303)
    except InvalidField as invalid:
        dbs.rollback()
        flash(f"{invalid.message}", "error")
        return redirect(url_for("accounts.robots_page"), 303)
    dbs.commit()
    robot_registry().refresh()
    flash(f"Robot {robot.name} saved ({'enabled' if robot.enabled else 'disabled'}).", "success")
    return redirect(url_for("accounts.robots_page"), 303)


@blueprint.get("/api/admin/robots")
@login_required
def api_robots():  # type: ignore[no-untyped-def]
    """Every robot in the table (admins)."""
    try:
        return jsonify({"robots": [r.to_dict() for r in robot_admin.list_robots(get_session(), current_user)]})
    except Refused as refused:
        raise api_error(refused) from None


@blueprint.post("/api/admin/robots")
@login_required
def api_add_robot():  # type: ignore[no-untyped-def]
    """{name, title?, address}: adds a robot (admins)."""
    data, dbs = _json_body(), get_session()
    try:
        robot = robot_admin.add_robot(dbs, current_user, data.get("name"), data.get("title"), data.get("address"))
    except (Refused, InvalidField) as error:
        dbs.rollback()
        raise api_error(error) from None
    dbs.commit()
    robot_registry().refresh()
    return jsonify({"robot": robot_admin.RobotView(robot.id, robot.name, robot.title, robot.address,
                                                   robot.enabled).to_dict()}), 201


@blueprint.patch("/api/admin/robots/<int:robot_id>")
@login_required
def api_update_robot(robot_id: int):  # type: ignore[no-untyped-def]
    """{title?, address?, enabled?}: changes a robot (admins)."""
    data, dbs = _json_body(), get_session()
    try:
        robot = robot_admin.update_robot(
            dbs, current_user, clean_id(robot_id, "robot_id"), title=data.get("title"), address=data.get("address"),
            enabled=clean_flag(data["enabled"], "enabled") if "enabled" in data else None)
    except (Refused, InvalidField) as error:
        dbs.rollback()
        raise api_error(error) from None
    dbs.commit()
    robot_registry().refresh()
    return jsonify({"robot": robot_admin.RobotView(robot.id, robot.name, robot.title, robot.address,
                                                   robot.enabled).to_dict()})
