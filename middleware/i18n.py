"""The page's language: Flask-Babel chooses Spanish or English for each request, so templates and services say
`_("...")` and the catalogue in middleware/translations/ answers."""

from __future__ import annotations

from flask import Flask, request
from flask_babel import Babel

LANGUAGES = ("en", "es")


def _locale() -> str:
    return request.accept_languages.best_match(LANGUAGES) or LANGUAGES[0]


def init_app(app: Flask) -> None:
    Babel(app, locale_selector=_locale, default_translation_directories="translations")
