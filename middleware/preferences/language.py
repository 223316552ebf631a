"""The language picker: POST /language stores the language a person chose (their `language` preference when signed
in, the browser session otherwise) and goes back to the page they were on."""

from __future__ import annotations

import json

from flask import Blueprint, redirect, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user
from sqlalchemy import select

from middleware import i18n
from middleware.auth.routes import safe_next_url
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.models import UserPreference
from middleware.models.accounts import utc_now

blueprint = Blueprint("language", __name__)


@blueprint.post("/language")
def choose() -> ResponseReturnValue:
    """Form fields: language (en or es), next (a path on this site; the lab's first page otherwise)."""
    language = i18n.supported(request.form.get("language"))
    if language is None or request.form.get("language") not in i18n.LANGUAGES:
        raise ApiError(400, "invalid_field", gettext("language must be one of: %(value)s.",
                                                     value=', '.join(i18n.LANGUAGES)), "language")
    i18n.remember_chosen_language(language)
    if current_user.is_authenticated:
        user_id = int(current_user.get_id())
        session = get_session()
        preference = session.scalar(select(UserPreference).where(
            UserPreference.user_id == user_id, UserPreference.key == i18n.LANGUAGE_PREFERENCE_KEY))
        if preference is None:
            session.add(UserPreference(user_id=user_id, key=i18n.LANGUAGE_PREFERENCE_KEY,
                                       value_json=json.dumps(language)))
        else:
            preference.value_json, preference.updated_at = json.dumps(language), utc_now()
    return redirect(safe_next_url(request.form.get("next")) or url_for("home"))
