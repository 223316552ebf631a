"""Invitations: tutors invite to their course and admins anyone, by a link that creates one account."""

from __future__ import annotations

from flask import flash, jsonify, redirect, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required, logout_user
from sqlalchemy import select

from middleware.accounts import invitations
from middleware.accounts.schemas import clean_invitation_days, clean_optional_id
from middleware.accounts.web import back_url, blueprint
from middleware.api.contract import ID, OBJECT, STRING, about, described, nullable, obj
from middleware.auth import sessions
from middleware.db import discard_changes, get_session
from middleware.errors import Refused, flashed, unless_refused
from middleware.i18n import N_
from middleware.models import Course
from middleware.web import json_body, now


@blueprint.get("/admin/invitations")
@login_required
def invitations_page() -> ResponseReturnValue:
    """Every invitation and the form to invite anyone (admins)."""
    views = invitations.list_invitations(get_session(), current_user, None, now())
    return render_template("accounts/invitations.html", invitations=views, errors={},
                           courses=get_session().scalars(select(Course).order_by(Course.code)).all())


@blueprint.post("/invitations")
@login_required
def invitations_create() -> ResponseReturnValue:
    """Creates an invitation (a tutor for their course, an admin for anyone) and shows its link once."""
    back = back_url()

    def create() -> ResponseReturnValue:
        course_id = clean_optional_id(request.form.get("course_id"), "course_id")
        invitation, token = invitations.create_invitation(
            get_session(), current_user, request.form.get("role") or "student", course_id,
            clean_invitation_days(request.form.get("days")), now())
        link = url_for("accounts.join", token=token, _external=True)
        return render_template("accounts/invitation_created.html", link=link, invitation=invitation,
                               back=back), 200, {"Cache-Control": "no-store"}

    return unless_refused(create, flashed(back))


@blueprint.post("/api/invitations")
@login_required
@described(
    body=obj(
        role=about("student (the default) or tutor"),
        course_id=about("a course's id, or null"),
        days=about("days it stays valid"),
    ),
    answers={201: obj(("id", "role"), id=ID, role=STRING, course_id=nullable(ID))},
)
def api_create_invitation() -> ResponseReturnValue:
    """{role, course_id?, days?}: an invitation link, returned once."""
    data = json_body()
    invitation, token = invitations.create_invitation(
        get_session(), current_user, data.get("role") or "student",
        clean_optional_id(data.get("course_id"), "course_id"), clean_invitation_days(data.get("days")), now())
    return jsonify({"id": invitation.id, "role": invitation.role, "course_id": invitation.course_id,
                    "expires_at": invitation.expires_at.isoformat(),
                    "url": url_for("accounts.join", token=token, _external=True)}), 201, {"Cache-Control": "no-store"}


@blueprint.post("/invitations/<int:invitation_id>/revoke")
@login_required
def invitations_revoke(invitation_id: int) -> ResponseReturnValue:
    """Withdraws a pending invitation from the page that lists it."""
    back = back_url()

    def revoke() -> ResponseReturnValue:
        invitations.revoke_invitation(get_session(), current_user, invitation_id, now())
        flash(gettext("The invitation was withdrawn: its link no longer works."), "success")
        return redirect(back, 303)

    return unless_refused(revoke, flashed(back))


@blueprint.delete("/api/invitations/<int:invitation_id>")
@login_required
@described(answers={200: obj(("invitation",), invitation=OBJECT)}, refusals=(409,))
def api_revoke_invitation(invitation_id: int) -> ResponseReturnValue:
    """Withdraws a pending invitation; answers it as lists show it."""
    view = invitations.revoke_invitation(get_session(), current_user, invitation_id, now())
    return jsonify({"invitation": view.to_dict()})


UNUSABLE = {  # said through gettext when shown
    "unknown": (404, N_("This invitation link is not valid"),
                N_("The link is not one we issued. Check that you copied all of it, or ask your tutor for a new one.")),
    "expired": (410, N_("This invitation has expired"),
                N_("Invitation links last a few days. Ask your tutor or the lab's admin for a new one.")),
    "used": (410, N_("This invitation has already been used"),
             N_("Each link creates one account. If it was you, log in; otherwise ask for a new link.")),
    "revoked": (410, N_("This invitation was withdrawn"),
                N_("The person who invited you withdrew this link. Ask them for a new one if you still need an "
                   "account.")),
}


def _join_unusable(reason: str) -> ResponseReturnValue:
    status, title, message = UNUSABLE[reason]
    return render_template("accounts/join_invalid.html", title=gettext(title), message=gettext(message),
                           reason=reason), status


@blueprint.get("/join/<token>")
def join(token: str) -> ResponseReturnValue:
    """The form that turns an invitation link into an account."""
    try:
        invitation, course = invitations.find_usable(get_session(), token, now())
    except invitations.InvitationUnusable as unusable:
        return _join_unusable(unusable.reason)
    return render_template("accounts/join.html", invitation=invitation, course=course, token=token,
                           errors={}, username=""), 200, {"Cache-Control": "no-store"}


@blueprint.post("/join/<token>")
def join_submit(token: str) -> ResponseReturnValue:
    """Creates the account, enrols it, logs it in and opens the lab."""
    username = request.form.get("username", "")[:128]

    def accept() -> ResponseReturnValue:
        user = invitations.accept(get_session(), token, username, request.form.get("password", "")[:300],
                                  request.form.get("password_again", "")[:300], now())
        if current_user.is_authenticated:
            logout_user()
        sessions.begin(user)
        flash(gettext("Welcome, %(username)s. Your account is ready.", username=user.username), "success")
        return redirect(url_for("lab.index"), 303)

    def form_again(refused: Refused) -> ResponseReturnValue:
        invitation, course = invitations.find_usable(get_session(), token, now())
        return render_template("accounts/join.html", invitation=invitation, course=course, token=token,
                               errors={refused.field or "username": refused.message}, username=username), 400

    try:
        return unless_refused(accept, form_again)
    except invitations.InvitationUnusable as unusable:
        discard_changes()  # the link went while this form was filled in: nothing of the attempt stays
        return _join_unusable(unusable.reason)
