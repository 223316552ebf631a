"""The built-in exercises' code templates say their comments in the reader's language (catalogue.in_language): each
comment of every template is a message of the catalogue, translated in Spanish; a Spanish template is the same Python
(the same tokens but comments, English names) and still fits the template's width; an English one is the stored text
byte for byte; a comment the catalogue does not know (a student's own) and code that does not tokenize stay as
written."""

from __future__ import annotations

import io
import tokenize
from collections.abc import Iterator
from pathlib import Path

import pytest
from flask import Flask
from flask_babel import Babel, force_locale  # type: ignore[import-untyped]

from middleware.exercises.catalogue import BUILT_IN, TEMPLATE_COMMENTS, comments, in_language

TRANSLATIONS = Path(__file__).resolve().parents[3] / "middleware" / "translations"
TEMPLATES = {entry["slug"]: entry["template"] for entry in BUILT_IN}


@pytest.fixture(scope="module")
def app() -> Flask:
    """A bare app with the lab's real catalogues (the middleware's own Babel set-up, without its database)."""
    app = Flask(__name__)
    Babel(app, default_translation_directories=str(TRANSLATIONS))
    return app


@pytest.fixture
def spanish(app: Flask) -> Iterator[None]:
    with app.test_request_context(), force_locale("es"):
        yield


def code_tokens(code: str) -> list[tuple[int, str]]:
    """What Python runs of code: its tokens without comments and line ends (a wrapped comment adds lines)."""
    skipped = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE}
    return [(t.type, t.string) for t in tokenize.generate_tokens(io.StringIO(code).readline) if t.type not in skipped]


def test_every_comment_of_a_template_is_a_message_and_every_message_a_comment() -> None:
    said = {text for code in TEMPLATES.values() for *_, text in comments(code)}
    assert said - set(TEMPLATE_COMMENTS) == set(), "a template's comment the catalogue does not know"
    assert set(TEMPLATE_COMMENTS) - said == set(), "a message no template says any more"


@pytest.mark.parametrize("slug", sorted(TEMPLATES))
def test_a_spanish_reader_gets_the_same_program_with_spanish_comments(spanish: None, slug: str) -> None:
    english = TEMPLATES[slug]
    code = in_language(english)
    assert code != english
    assert code_tokens(code) == code_tokens(english)  # the program itself is untouched: English names, same Python
    compile(code, f"{slug}.py", "exec")
    assert max(map(len, code.splitlines())) <= 116
    written = [text for *_, text in comments(code)]
    assert not set(written) & set(TEMPLATE_COMMENTS), written  # no comment left in English
    assert code.endswith("\n")


def test_the_spanish_follow_line_template_reads_as_spanish(spanish: None) -> None:
    code = in_language(TEMPLATES["follow-line"])
    assert "# El bucle va a 20 Hz: cada robot.tick() espera al siguiente periodo" in code
    assert "robot.set_velocity(0.0, 0.0)  # se ha perdido la línea: ¿dónde la viste por última vez?" in code
    assert "offset = robot.line_position()" in code


@pytest.mark.parametrize("slug", sorted(TEMPLATES))
def test_an_english_reader_and_no_request_get_the_stored_template(app: Flask, slug: str) -> None:
    assert in_language(TEMPLATES[slug]) == TEMPLATES[slug]  # no request: gettext says the English
    with app.test_request_context(), force_locale("en"):
        assert in_language(TEMPLATES[slug]) == TEMPLATES[slug]


def test_a_students_own_comments_and_unfinished_code_stay_as_written(spanish: None) -> None:
    own = "from telelab import robot\n# Camera\nwhile robot.tick():  # beams pointing left, my way\n    pass\n"
    assert in_language(own) == own  # "Camera" is a message, but not a template's comment
    unfinished = 'print("# beams pointing left"\n# beams pointing left\n'
    assert in_language(unfinished) == unfinished
    mixed = 'print("# beams pointing left")  # beams pointing left\n'
    assert in_language(mixed) == 'print("# beams pointing left")  # haces que apuntan a la izquierda\n'
