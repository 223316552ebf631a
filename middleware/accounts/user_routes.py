"""Accounts: one's own password, and the admins' users table (create, disable or enable, re-role) with
password resets (admins; tutors for their students)."""

from __future__ import annotations

from collections.abc import Callable

from flask import flash, jsonify, redirect, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.accounts import services
from middleware.accounts.schemas import clean_flag
from middleware.accounts.web import blueprint
from middleware.api.contract import BOOLEAN, OBJECT, STRING, about, array, described, obj, text
from middleware.auth import sessions
from middleware.auth.schemas import InvalidField
from middleware.auth.services import change_own_password
from middleware.db import get_session
from middleware.errors import flashed, unless_refused
from middleware.i18n import role_name
from middleware.models import User
from middleware.web import json_body, now

# --- own password ---------------------------------------------------------------------------------


def _change_own_password(current: str, new: object) -> None:
    """Changes current_user's password; the form's and the API's field is new_password, the rule's password."""
    try:
        change_own_password(get_session(), current_user, current, new)  # type: ignore[arg-type]
    except InvalidField as invalid:
        if invalid.field != "password":
            raise
        raise InvalidField("new_password", invalid.message) from None
    sessions.password_changed(current_user)


@blueprint.get("/account/password")
@login_required
def password_page() -> ResponseReturnValue:
    """The form to change one's own password."""
    return render_template("accounts/password.html", errors={})


@blueprint.post("/account/password")
@login_required
def password_submit() -> ResponseReturnValue:
    """Changes one's own password (the current one is required)."""
    new, again = request.form.get("new_password", ""), request.form.get("new_password_again", "")

    def change() -> ResponseReturnValue:
        if new != again:
            raise InvalidField("new_password_again", gettext("The two new passwords differ; type the same one twice."))
        _change_own_password(request.form.get("current_password", ""), new)
        flash(gettext("Your password has been changed."), "success")
        return redirect(url_for("lab.index"), 303)

    return unless_refused(change, lambda refused: (render_template(
        "accounts/password.html", errors={refused.field or "current_password": refused.message}), refused.status))


@blueprint.post("/api/account/password")
@login_required
@described(
    body=obj(("current_password", "new_password"), current_password=text(), new_password=text()),
    answers={200: obj(("changed",), changed=BOOLEAN)},
    refusals=(429,),
)
def api_password() -> ResponseReturnValue:
    """{current_password, new_password}: changes one's own password."""
    data = json_body()
    _change_own_password(str(data.get("current_password") or ""), data.get("new_password"))
    return jsonify({"changed": True})


# --- accounts (admins) and password resets ---------------------------------------------------------


def _users_page(errors: dict[str, str] | None = None, form: dict[str, str] | None = None,
                status: int = 200) -> ResponseReturnValue:
    users = services.list_users(get_session(), current_user)
    throttles = services.login_throttles(get_session(), current_user, now())
    return render_template("accounts/users.html", users=users, throttles=throttles, errors=errors or {},
                           form=form or {}, roles=["student", "tutor", "admin"]), status


@blueprint.get("/admin/users")
@login_required
def users_page() -> ResponseReturnValue:
    """Every account, with forms to create, disable or enable, re-role and reset (admins)."""
    return _users_page()


@blueprint.post("/admin/users")
@login_required
def users_create() -> ResponseReturnValue:
    """Creates an account and shows its generated password once."""
    def create() -> ResponseReturnValue:
        user, password = services.create_account(get_session(), current_user, request.form.get("username", ""),
                                                 request.form.get("role", ""))
        return _password_shown(user.username, password, created=True)

    return unless_refused(create, lambda refused: _users_page(
        {refused.field or "username": refused.message}, request.form.to_dict(), refused.status))


def _password_shown(username: str, password: str, created: bool = False) -> ResponseReturnValue:
    response = render_template("accounts/password_shown.html", username=username, password=password, created=created)
    return response, 200, {"Cache-Control": "no-store"}


def _admin_form_action(action: Callable[[], User]) -> ResponseReturnValue:
    def act() -> ResponseReturnValue:
        user = action()
        flash(gettext("%(username)s: active, %(role)s.", username=user.username, role=role_name(user.role))
              if user.is_active else gettext("%(username)s: disabled, %(role)s.", username=user.username,
                                             role=role_name(user.role)), "success")
        return redirect(url_for("accounts.users_page"), 303)

    return unless_refused(act, flashed(url_for("accounts.users_page")))


@blueprint.post("/admin/users/<int:user_id>/active")
@login_required
def users_set_active(user_id: int) -> ResponseReturnValue:
    """Disables (active=0) or enables (active=1) an account."""
    return _admin_form_action(lambda: services.set_active(
        get_session(), current_user, user_id, clean_flag(request.form.get("active", ""), "active")))


@blueprint.post("/admin/users/<int:user_id>/role")
@login_required
def users_set_role(user_id: int) -> ResponseReturnValue:
    """Changes an account's role."""
    return _admin_form_action(lambda: services.change_role(get_session(), current_user, user_id,
                                                           request.form.get("role")))


@blueprint.post("/users/<int:user_id>/reset-password")
@login_required
def reset_password(user_id: int) -> ResponseReturnValue:
    """Gives an account a generated password and shows it once (admins; tutors for their students)."""
    def reset() -> ResponseReturnValue:
        user, password = services.reset_password(get_session(), current_user, user_id)
        return _password_shown(user.username, password)

    return unless_refused(reset, flashed(request.referrer or url_for("lab.index")))


@blueprint.get("/api/users")
@login_required
@described(answers={200: obj(("users",), users=array(OBJECT))})
def api_users() -> ResponseReturnValue:
    """Every account (admins)."""
    return jsonify({"users": [u.to_dict() for u in services.list_users(get_session(), current_user)]})


@blueprint.post("/api/users")
@login_required
@described(
    body=obj(
        ("username", "role"),
        username=about("2-64 lowercase letters, digits, ., _ or -"),
        role=about("student, tutor or admin"),
    ),
    answers={201: obj(("user", "password"), user=OBJECT, password=STRING)},
    refusals=(409,),
)
def api_create_user() -> ResponseReturnValue:
    """{username, role}: creates an account; the answer holds the generated password, once."""
    data = json_body()
    user, password = services.create_account(get_session(), current_user, data.get("username"), data.get("role"))
    body = services.UserView(user.id, user.username, user.role, user.is_active).to_dict()
    return jsonify({"user": body, "password": password}), 201, {"Cache-Control": "no-store"}


@blueprint.patch("/api/users/<int:user_id>")
@login_required
@described(
    body=obj(role=about("student, tutor or admin"), is_active=about("true or false")),
    answers={200: obj(("user",), user=OBJECT)},
    refusals=(409,),
)
def api_update_user(user_id: int) -> ResponseReturnValue:
    """{role?, is_active?}: changes an account (admins)."""
    data, dbs = json_body(), get_session()
    services.require_admin(current_user)
    user = services.get_user(dbs, user_id)
    if "role" in data:
        user = services.change_role(dbs, current_user, user_id, data["role"])
    if "is_active" in data:
        user = services.set_active(dbs, current_user, user_id, clean_flag(data["is_active"], "is_active"))
    return jsonify({"user": services.UserView(user.id, user.username, user.role, user.is_active).to_dict()})


@blueprint.post("/api/users/<int:user_id>/password-reset")
@login_required
@described(answers={200: obj(("username", "password"), username=STRING, password=STRING)})
def api_reset_password(user_id: int) -> ResponseReturnValue:
    """Gives an account a generated password, returned once (admins; tutors for their students)."""
    user, password = services.reset_password(get_session(), current_user, user_id)
    return jsonify({"username": user.username, "password": password}), 200, {"Cache-Control": "no-store"}
