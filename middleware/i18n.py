"""The page's language: Flask-Babel chooses Spanish or English for each request, so templates and services say
`_("...")` and the catalogue in middleware/translations/ answers.

The language is, in order: the one the user chose (their `language` preference; before signing in, the one chosen
on the sign-in page, kept in the session), the one their LMS launched them with (`remember_launch_locale`), the
browser's Accept-Language, English."""

from __future__ import annotations

import re

from babel.numbers import get_decimal_symbol
from flask import Flask, current_app, g, has_request_context, request, session
from flask_babel import Babel, get_locale, gettext, lazy_gettext  # type: ignore[import-untyped]
from flask_login import current_user
from sqlalchemy import select

from middleware.db import session_factory
from middleware.models import UserPreference

LANGUAGES = ("en", "es")
# Each language in its own words, for the picker.
LANGUAGE_NAMES = {"en": "English", "es": "Español"}
# The user's own choice, a preference like any other (PUT /api/me/preferences/language {"value": "es"} sets it too).
LANGUAGE_PREFERENCE_KEY = "language"
# The roles' names as pages show them (the stored role stays the English word).
ROLE_NAMES = {"student": lazy_gettext("student"), "tutor": lazy_gettext("tutor"), "admin": lazy_gettext("admin")}
_CHOSEN_KEY = "language"
_LAUNCH_KEY = "launch_locale"


def supported(locale: object) -> str | None:
    """The supported language a locale names ("es", "es-ES", "es_419", "EN"), or None."""
    if not isinstance(locale, str):
        return None
    language = locale.strip().replace("_", "-").split("-")[0].lower()
    return language if language in LANGUAGES else None


def remember_launch_locale(locale: str) -> None:
    """Keeps the locale an LTI launch named (its launch_presentation.locale claim) for this browser session; a
    language the lab has not is ignored. The user's own choice still comes first."""
    language = supported(locale)
    if language is None:
        session.pop(_LAUNCH_KEY, None)
    else:
        session[_LAUNCH_KEY] = language


def remember_chosen_language(language: str) -> None:
    """Keeps a language the person chose in this browser session (before they sign in, or beside their preference)."""
    chosen = supported(language)
    if chosen is not None:
        session[_CHOSEN_KEY] = chosen


def _user_choice() -> str | None:
    if not current_user.is_authenticated:
        return None
    query = select(UserPreference.value_json).where(
        UserPreference.user_id == int(current_user.get_id()), UserPreference.key == LANGUAGE_PREFERENCE_KEY)
    if "db_session" in g:  # the request's unit of work, as it stands (nothing of it flushed to ask)
        with g.db_session.no_autoflush:
            text = g.db_session.scalar(query)
    else:  # none yet (a WebSocket's refusal, a page that reads nothing): a session of its own, closed at once, so
        # no connection is held for the rest of a long-lived context
        with session_factory(current_app)() as own:
            text = own.scalar(query)
    return supported(text.strip('"')) if text else None


def _locale() -> str:
    if not has_request_context():
        return LANGUAGES[0]
    return (_user_choice() or supported(session.get(_CHOSEN_KEY)) or supported(session.get(_LAUNCH_KEY))
            or request.accept_languages.best_match(LANGUAGES) or LANGUAGES[0])


def current_language() -> str:
    """The request's language code ("en" or "es"); English outside a request."""
    if not has_request_context():
        return LANGUAGES[0]
    return str(get_locale() or LANGUAGES[0]).split("_")[0]


def N_(text: str) -> str:  # noqa: N802 (gettext's "mark for the catalogue, translate later")
    return text


# Stored English sentences with values (a grader's feedback): their pattern, and the message that says them.
_WITH_VALUES = (
    (re.compile(r"Correct \((?P<shown>.*)\)\."), N_("Correct (%(shown)s).")),
    (re.compile(r"Outside the accepted range \((?P<shown>.*)\)\."), N_("Outside the accepted range (%(shown)s).")),
    (re.compile(r"The right choice was: (?P<choice>.*)\."), N_("The right choice was: %(choice)s.")),
    (re.compile(r"The right choices were: (?P<choices>.*)\."), N_("The right choices were: %(choices)s.")),
    (re.compile(r"Partly right; the right choices were: (?P<choices>.*)\."),
     N_("Partly right; the right choices were: %(choices)s.")),
    (re.compile(r"An accepted answer: (?P<answer>.*)\."), N_("An accepted answer: %(answer)s.")),
    (re.compile(r"(?P<unit>.*) is not a unit of the same quantity as (?P<expected>.*)\."),
     N_("%(unit)s is not a unit of the same quantity as %(expected)s.")),
    # The experimental task's grader (trace_grading.py): a measure, then the rubric's share, two sentences.
    (re.compile(r"The robot ended (?P<error>\S+) m from \((?P<x>[^,]+), (?P<y>[^)]+)\)\."),
     N_("The robot ended %(error)s m from (%(x)s, %(y)s).")),
    (re.compile(r"The robot travelled (?P<travel>\S+) m; the task needs at least (?P<needed>\S+) m along the wall\."),
     N_("The robot travelled %(travel)s m; the task needs at least %(needed)s m along the wall.")),
    (re.compile(r"The RMS distance error to the wall was (?P<error>\S+) m over (?P<travel>\S+) m\."),
     N_("The RMS distance error to the wall was %(error)s m over %(travel)s m.")),
    (re.compile(r"The reported pose was (?P<error>\S+) m from the robot's true position\."),
     N_("The reported pose was %(error)s m from the robot's true position.")),
    (re.compile(r"The zone you marked overlaps the obstacles with IoU (?P<iou>\S+) \(precision (?P<precision>\S+), "
                r"recall (?P<recall>\S+)\)\."),
     N_("The zone you marked overlaps the obstacles with IoU %(iou)s (precision %(precision)s, recall %(recall)s).")),
    (re.compile(r"Rubric: (?P<percent>\d+)% of the points\."), N_("Rubric: %(percent)s%% of the points.")),
)
# The values above that are the grader's numbers (a choice's or unit's text stays as its author wrote it).
_NUMBERS = {"shown", "error", "x", "y", "travel", "needed", "iou", "precision", "recall", "percent"}
# Where a stored feedback of several sentences is cut to say each (a full stop, a space, a capital).
_SENTENCE_END = re.compile(r"(?<=\.) (?=[A-Z])")


_DECIMAL_POINT = re.compile(r"(?<=\d)\.(?=\d)")


def translated(text: str) -> str:
    """A stored English sentence the catalogue may know (a grader's feedback), in the page's language; a feedback
    of several sentences is said sentence by sentence when the catalogue has it only so."""
    if not text:
        return text
    whole = _translated_sentence(text)
    if whole != text or current_language() == LANGUAGES[0]:
        return whole
    return " ".join(_translated_sentence(sentence) for sentence in _SENTENCE_END.split(text))


def _translated_sentence(text: str) -> str:
    for pattern, message in _WITH_VALUES:
        if match := pattern.fullmatch(text):  # the grader's numbers ("8 ± 0.5 m") with the page's decimal sign
            values = {name: _DECIMAL_POINT.sub(_decimal_sign(), value) if name in _NUMBERS else value
                      for name, value in match.groupdict().items()}
            return str(gettext(message, **values))
    return str(gettext(text))


def _decimal_sign() -> str:
    """The decimal sign of the page's language ("." in English, "," in Spanish)."""
    return str(get_decimal_symbol(current_language()))


def role_name(role: str) -> str:
    """A role's name in the page's language ("estudiante"); an unknown role as it is."""
    return str(ROLE_NAMES[role]) if role in ROLE_NAMES else role


def translate_panels(panels: list[dict[str, object]]) -> list[dict[str, object]]:
    """Console panel descriptors with their title and help in the page's language: the robot's words and the
    middleware's are English, marked in translations/robot_words.py; words the catalogue has not stay English."""
    for descriptor in panels:
        for key in ("title", "help"):
            text = descriptor.get(key)
            if isinstance(text, str) and text:
                descriptor[key] = _sentences(text)
        for parameter in descriptor.get("schema") or []:  # type: ignore[attr-defined]
            if isinstance(parameter, dict) and isinstance(parameter.get("help"), str) and parameter["help"]:
                parameter["help"] = _sentences(parameter["help"])
    return panels


def _sentences(text: str) -> str:
    """text translated whole, or as a known first sentence and the rest (a skill's help: its class, then its own)."""
    whole = str(gettext(text))
    if whole != text or current_language() == LANGUAGES[0]:
        return whole
    for cut in re.finditer(r"\. ", text):
        head = text[:cut.start() + 1]
        translated = str(gettext(head))
        if translated != head:
            return f"{translated} {_sentences(text[cut.end():])}"
    return text


def init_app(app: Flask) -> None:
    Babel(app, locale_selector=_locale, default_translation_directories="translations")

    @app.context_processor
    def _language() -> dict[str, object]:
        return {"page_language": current_language(), "language_names": LANGUAGE_NAMES, "role_name": role_name,
                "translated": translated}
