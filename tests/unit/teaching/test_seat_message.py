"""A class seat's outcome is stored in English (its robot starts on a thread with no request) and read in the
reader's language: a catalogue sentence is said again, one with values in it stays as stored."""

from __future__ import annotations

from pathlib import Path

from flask import Flask
from flask_babel import Babel, force_locale  # type: ignore[import-untyped]

from middleware.teaching.class_sessions import NOT_STARTED, STOPPED_WHILE_OPEN, seat_message

TRANSLATIONS = Path(__file__).resolve().parents[3] / "middleware" / "translations"


def test_a_seats_stored_english_sentence_is_read_in_the_readers_language() -> None:
    app = Flask(__name__)
    Babel(app, default_translation_directories=str(TRANSLATIONS))
    with app.test_request_context(), force_locale("es"):
        assert seat_message(NOT_STARTED) == "El robot no arrancó; el tutor puede volver a iniciar la sesión."
        assert seat_message(STOPPED_WHILE_OPEN) != STOPPED_WHILE_OPEN
        assert seat_message("The farm is full (12 of 12 robots).") == "The farm is full (12 of 12 robots)."
        assert seat_message("") == ""
    with app.test_request_context(), force_locale("en"):
        assert seat_message(NOT_STARTED) == NOT_STARTED
