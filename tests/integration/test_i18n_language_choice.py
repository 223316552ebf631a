"""Which language a page speaks, over HTTP on the live app: the person's own choice first (kept with their account
once signed in), then the LTI launch's locale, then the browser's Accept-Language; <html lang> says which; a bad
choice is refused naming its field and changes nothing; moments are written in the page's language."""

from __future__ import annotations

import re
from datetime import UTC, datetime

import pytest
from flask import jsonify

from tests.conftest import LabClient, LiveServer

SPANISH = {"Accept-Language": "es-ES,es;q=0.9,en;q=0.5"}
ENGLISH = {"Accept-Language": "en-GB,en;q=0.9"}


def lang_of(body: str) -> str:
    match = re.search(r'<html lang="([^"]+)"', body)
    assert match, body[:200]
    return match.group(1)


@pytest.fixture
def launched(app):
    """A stand-in for the LTI launch (middleware/lti calls the same function with the launch's locale claim)."""
    from middleware import i18n

    def launch(locale: str):
        i18n.remember_launch_locale(locale)
        return jsonify({"ok": True})

    app.add_url_rule("/test-launch/<locale>", "test_launch", launch)
    return app


def stored_language(app, username: str) -> object:
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import User
    from middleware.preferences.stored import stored_value

    with session_factory(app)() as session:
        user_id = session.scalar(select(User.id).where(User.username == username))
        return stored_value(session, user_id, "language")


def choose(client: LabClient, language: str, next_path: str = "/login", headers: dict[str, str] | None = None):
    token = client.csrf_token(next_path)
    return client.request("POST", "/language", {"language": language, "next": next_path, "csrf_token": token},
                          headers=headers)


def test_the_browser_language_picks_spanish_or_english_and_lang_says_which(live_server: LiveServer) -> None:
    client = LabClient(live_server.url)
    status, _, body = client.request("GET", "/login", headers=SPANISH)
    assert status == 200 and lang_of(body) == "es"
    assert "Entra en el laboratorio" in body and "Log in to the lab" not in body
    assert 'aria-label="Principal"' not in body  # the menu is for people signed in
    _, _, body = client.request("GET", "/login", headers=ENGLISH)
    assert lang_of(body) == "en" and "Log in to the lab" in body
    _, _, body = client.request("GET", "/login", headers={"Accept-Language": "de-DE,fr;q=0.8"})
    assert lang_of(body) == "en"  # a language the lab has not: English


def test_the_launch_locale_beats_the_browser_and_the_persons_choice_beats_both(launched,
                                                                                 live_server: LiveServer) -> None:
    client = LabClient(live_server.url)
    assert client.request("GET", "/test-launch/es_ES")[0] == 200
    _, _, body = client.request("GET", "/login", headers=ENGLISH)
    assert lang_of(body) == "es"
    assert client.request("GET", "/test-launch/fr")[0] == 200  # a locale the lab has not: the browser's again
    assert lang_of(client.request("GET", "/login", headers=ENGLISH)[2]) == "en"

    client.request("GET", "/test-launch/es")
    status, headers, _ = choose(client, "en", headers=ENGLISH)
    assert status == 302 and headers["Location"].endswith("/login")
    assert lang_of(client.request("GET", "/login", headers=SPANISH)[2]) == "en"


def test_a_signed_in_choice_is_kept_with_the_account_for_the_next_session(app, live_server: LiveServer) -> None:
    first = LabClient(live_server.url)
    assert first.login() == 302
    status, headers, _ = choose(first, "es", next_path="/bookings?tz=UTC", headers=ENGLISH)
    assert status == 302 and headers["Location"].endswith("/bookings?tz=UTC")
    _, _, body = first.request("GET", "/bookings?tz=UTC", headers=ENGLISH)
    assert lang_of(body) == "es" and "Reservas" in body and ">estudiante<" in body
    assert stored_language(app, "student1") == "es"

    later = LabClient(live_server.url)  # another browser, set to English
    assert later.login() == 302
    _, _, body = later.request("GET", "/lab", headers=ENGLISH)
    assert lang_of(body) == "es" and "Elige un robot para abrir su consola." in body


def test_a_language_the_lab_has_not_is_refused_naming_the_field_and_nothing_is_stored(
        app, live_server: LiveServer) -> None:
    client = LabClient(live_server.url)
    assert client.login() == 302
    for language in ("de", "", "ES", "es-ES", "x" * 5000):
        status, _, body = choose(client, language, next_path="/lab")
        assert status == 400 and "language" in body, language
    assert stored_language(app, "student1") is None
    assert lang_of(client.request("GET", "/lab", headers=ENGLISH)[2]) == "en"


def test_a_choice_never_redirects_off_the_site(live_server: LiveServer) -> None:
    client = LabClient(live_server.url)
    status, headers, _ = choose(client, "es", next_path="/login")
    token = client.csrf_token("/login")
    for outside in ("https://evil.example/", "//evil.example/x", "javascript:alert(1)"):
        status, headers, _ = client.request("POST", "/language", {"language": "es", "next": outside,
                                                                  "csrf_token": token})
        assert status == 302 and headers["Location"] in ("/", f"{live_server.url}/"), headers["Location"]


def test_moments_are_written_in_the_pages_language(app) -> None:
    from middleware.wording import moment_words

    moment = datetime(2026, 11, 23, 21, 10, tzinfo=UTC)
    assert moment_words(moment) == "Mon 23 Nov 2026, 21:10 UTC"  # outside a request: English
    with app.test_request_context("/", headers=SPANISH):
        assert moment_words(moment) == "lun 23 nov 2026, 21:10 UTC"
    with app.test_request_context("/", headers=ENGLISH):
        assert moment_words(moment) == "Mon 23 Nov 2026, 21:10 UTC"
