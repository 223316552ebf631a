"""Login throttles for admins: the section of /admin/users that lists them, and clearing one (form and API)."""

from __future__ import annotations

from flask import flash, jsonify, redirect, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.accounts import services
from middleware.accounts.web import blueprint
from middleware.api.contract import ANY, OBJECT, about, array, described, obj
from middleware.db import get_session
from middleware.errors import flashed, unless_refused
from middleware.web import json_body, now


@blueprint.post("/admin/throttles/clear")
@login_required
def throttles_clear() -> ResponseReturnValue:
    """Clears one throttle from the accounts page: an address, or one username tried from it."""
    address, username = request.form.get("address"), request.form.get("username")
    back = url_for("accounts.users_page", _anchor="throttles")

    def clear() -> ResponseReturnValue:
        cleared = services.clear_login_throttle(get_session(), current_user, address, username)
        whose = (gettext("%(username)s from %(address)s", username=username, address=address) if username
                 else gettext("every account from %(address)s", address=address))
        flash(gettext("Cleared %(count)s failed login of %(whose)s.", count=cleared, whose=whose) if cleared == 1
              else gettext("Cleared %(count)s failed logins of %(whose)s.", count=cleared, whose=whose), "success")
        return redirect(back, 303)

    return unless_refused(clear, flashed(back))


@blueprint.get("/api/admin/login-throttles")
@login_required
@described(answers={200: obj(("throttles",), throttles=array(OBJECT))})
def api_throttles() -> ResponseReturnValue:
    """The login keys being slowed now or at their next failure (admins)."""
    throttles = services.login_throttles(get_session(), current_user, now())
    return jsonify({"throttles": [t.to_dict() for t in throttles]})


@blueprint.delete("/api/admin/login-throttles")
@login_required
@described(
    body=obj(
        ("address",),
        address=about("the address whose failed logins are forgotten"),
        username=about("only this username's, when given"),
    ),
    answers={200: obj(("cleared",), cleared=ANY)},
)
def api_clear_throttle() -> ResponseReturnValue:
    """{address, username?}: forgets the failed logins from address (of username only, when given)."""
    data = json_body()
    cleared = services.clear_login_throttle(get_session(), current_user, data.get("address"), data.get("username"))
    return jsonify({"cleared": cleared})
