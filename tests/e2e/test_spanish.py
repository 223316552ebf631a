"""A student's first session and a tutor's correction, entirely in Spanish, in Chromium set to Spanish (es-ES) at
desktop (1280x800) and phone (390x844) sizes: every page says <html lang="es">, no English word is left where a
person reads, nothing scrolls sideways; screenshots in test-artifacts/spanish-*.png."""

from __future__ import annotations

import re
from datetime import UTC, datetime, timedelta

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer, add_test_account

pytestmark = pytest.mark.e2e

DESKTOP = {"width": 1280, "height": 800}
PHONE = {"width": 390, "height": 844}
# Words only English has, as the pages would show them untranslated (Spanish never writes these words).
ENGLISH = re.compile(
    r"\b(the|and|your|you|with|this|that|is|are|of|to|for|have|from|not|yet|Log|Save|Send|Start|Stop|Open|"
    r"Choose|Join|Leave|Loading|Waiting|Next|Back|Book|Cancel|Submit|Edit|Delete|Change|Password|Tests|Bookings|"
    r"Teaching|Plans|Courses|Camera|Turn|Queue|Drive|Speed|Heading|Online|Offline|Checking|Review|Mark|Comment|"
    r"connected|connecting|live|closed|answering|Question|answer|Correct)\b")


@pytest.fixture
def spanish_course(app) -> dict[str, int]:
    """A course taught in Spanish: tutor1 and student1, two questions and a timed test open now."""
    from middleware.assessment import bank
    from middleware.assessment.schemas import parse_exam, parse_question
    from middleware.db import session_factory
    from middleware.models import Course, CourseMembership, User

    with session_factory(app)() as session:
        tutor = add_test_account(session, "tutor1", "tutor")
        student = session.query(User).filter(User.username == "student1").one()
        course = Course(code="ROB-ES", title="Robótica móvil")
        session.add(course)
        session.flush()
        session.add_all([CourseMembership(course_id=course.id, user_id=tutor.id, role="tutor"),
                         CourseMembership(course_id=course.id, user_id=student.id, role="student")])
        choice = bank.add_question(session, tutor, course.id, parse_question(
            {"kind": "single", "prompt": "¿Deriva la odometría?", "choices": ["No", "Sí"], "correct": 1,
             "topics": ["odometría"]}))
        numeric = bank.add_question(session, tutor, course.id, parse_question(
            {"kind": "numeric", "prompt": "¿Alcance máximo del láser?", "value": 8, "tolerance": 0.5, "unit": "m",
             "topics": ["sensores"]}))
        now = datetime.now(UTC)
        exam = bank.create_exam(session, tutor, course.id, parse_exam({
            "title": "Sensores: prueba", "kind": "theory", "opens_at": (now - timedelta(minutes=1)).isoformat(),
            "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": 900,
            "question_ids": [choice.id, numeric.id]}))
        session.commit()
        return {"course": course.id, "exam": exam.id}


def english_left(tab) -> list[str]:
    """The lines a person reads on the page that hold an English word."""
    text = tab.evaluate("document.body.innerText")
    return [line.strip() for line in text.splitlines() if ENGLISH.search(line)]


def look(tab, name: str) -> None:
    """At desktop and phone sizes: Spanish, no English left, nothing wider than the screen; a screenshot of each."""
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    for size, viewport in (("desktop", DESKTOP), ("phone", PHONE)):
        tab.set_viewport_size(viewport)
        tab.wait_for_timeout(150)  # the menu folds on a phone (site-menu.js, on the media query's change)
        assert tab.evaluate("document.documentElement.lang") == "es", name
        assert not english_left(tab), f"{name} ({size}) still shows English: {english_left(tab)}"
        tab.screenshot(path=str(ARTIFACTS_DIR / f"spanish-{name}-{size}.png"), full_page=True)
        overflow = tab.evaluate("document.documentElement.scrollWidth - window.innerWidth")
        wide = tab.evaluate("""() => [...document.querySelectorAll('main *')]
          .filter((e) => e.getBoundingClientRect().right > window.innerWidth + 1)
          .slice(-3).map((e) => `${e.tagName}.${e.className} ${e.textContent.trim().slice(0, 40)}`)""")
        assert overflow <= 1, f"{name} ({size}) scrolls sideways by {overflow} px: {wide}"
    tab.set_viewport_size(DESKTOP)


def read_console_numbers(tab) -> None:
    """At desktop and phone sizes, the odometry and the drive pad's speeds write their numbers as Spanish does:
    "0,00" and "50 % · 0,25 m/s · 0,75 rad/s", never with a decimal point."""
    x_field = tab.locator('odometry-panel [data-field="x"]')
    speed = tab.locator("drive-pad #drive-speed-value")
    for size, viewport in (("desktop", DESKTOP), ("phone", PHONE)):
        tab.set_viewport_size(viewport)
        x_field.filter(has_text=",").wait_for()
        speed.filter(has_text="m/s").wait_for()
        x_m, speeds = x_field.text_content() or "", speed.text_content() or ""
        assert re.fullmatch(r"-?\d+,\d\d", x_m), f"odometry x ({size}): {x_m!r}"
        assert re.fullmatch(r"\d+ % · \d+,\d\d m/s · \d+,\d\d rad/s", speeds), f"drive pad ({size}): {speeds!r}"
        x_field.scroll_into_view_if_needed()
        tab.screenshot(path=str(ARTIFACTS_DIR / f"spanish-console-numbers-read-{size}.png"))
    tab.set_viewport_size(DESKTOP)


def spanish_tab(chromium):
    context = chromium.new_context(locale="es-ES", viewport=DESKTOP)
    tab = context.new_page()
    errors: list[str] = []
    tab.on("pageerror", lambda error: errors.append(str(error)))
    return context, tab, errors


def log_in(tab, live_server: LiveServer, username: str) -> None:
    tab.goto(f"{live_server.url}/login")
    tab.fill("#username", username)
    tab.fill("#password", STUDENT_PASSWORD)
    tab.get_by_role("button", name="Iniciar sesión").click()
    tab.locator('[data-field="username"]').wait_for()


def test_a_students_first_session_is_entirely_in_spanish(chromium, live_server: LiveServer, spanish_course) -> None:
    context, tab, errors = spanish_tab(chromium)
    try:
        tab.goto(f"{live_server.url}/login")
        tab.get_by_role("heading", name="Entra en el laboratorio").wait_for()
        look(tab, "login")
        tab.fill("#username", "student1")
        tab.fill("#password", "not-the-password")
        tab.get_by_role("button", name="Iniciar sesión").click()
        tab.locator("#login-error", has_text="Nombre de usuario o contraseña incorrectos").wait_for()
        log_in(tab, live_server, "student1")
        tab.get_by_role("heading", name="Robots").wait_for()
        assert tab.locator('[data-field="role"]').text_content() == "estudiante"
        look(tab, "robots")

        tab.locator('a.robot-card[data-robot="lab-1"]').click()
        tab.locator('[data-connection="drive"][data-phase="open"]').wait_for()
        tab.locator('[data-field="queue-summary"]', has_text="Tienes el control").wait_for()
        tab.locator("#camera-title", has_text="Cámara").wait_for(state="attached")
        look(tab, "console")
        for view in ("Navegar", "Percibir", "Chat"):
            tab.get_by_role("tab", name=view).click()
            tab.wait_for_timeout(300)
            assert not english_left(tab), f"console, {view}: {english_left(tab)}"
        tab.get_by_role("tab", name="Navegar").click()
        # The map says where the robot is as Spanish writes it: decimal commas, the pair split by a semicolon.
        summary = tab.locator('map-panel [data-field="map-summary"]')
        summary.filter(has_text="según la odometría").wait_for()
        said = summary.text_content() or ""
        assert re.search(r"Robot en \(-?\d+,\d\d; -?\d+,\d\d\) m según la odometría", said), said
        assert not re.search(r"\d\.\d", said) and "frente a el" not in said, said
        look(tab, "console-navigate")
        tab.get_by_role("tab", name="Conducir").click()
        read_console_numbers(tab)
        look(tab, "console-numbers")

        tab.goto(f"{live_server.url}/bookings")
        tab.get_by_role("heading", name="Reservas", exact=True).wait_for()
        look(tab, "bookings")

        tab.get_by_role("link", name="Pruebas").first.click()
        tab.get_by_role("link", name="Sensores: prueba").click()
        look(tab, "exam")
        tab.get_by_role("button", name="Empezar").click()
        tab.locator("#time-left").wait_for()
        tab.get_by_label("Sí").check()
        tab.locator("#save-status", has_text="Respuesta guardada.").wait_for(state="attached")
        tab.get_by_label("Valor").fill("7,9")  # a decimal comma, as Spanish writes it
        tab.get_by_label("Valor").press("Tab")
        tab.wait_for_function("document.getElementById('save-status').textContent === 'Respuesta guardada.'")
        look(tab, "attempt")
        tab.get_by_role("button", name="Entregar").click()
        tab.locator(".flash--success", has_text="Entregado. Tu intento corregido está abajo.").wait_for()
        tab.locator("#score").wait_for()
        look(tab, "corrected")
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"


def test_a_tutors_correction_is_entirely_in_spanish(chromium, app, live_server: LiveServer, spanish_course) -> None:
    from middleware.assessment import attempts
    from middleware.assessment.routes import server_now
    from middleware.db import session_factory
    from middleware.models import User

    with app.app_context(), session_factory(app)() as session:  # the student's attempt, handed in untouched
        student = session.query(User).filter(User.username == "student1").one()
        attempt = attempts.start_attempt(session, student, spanish_course["exam"], server_now())
        attempts.submit_attempt(session, student, attempt.id, server_now())  # nothing answered: marks of 0
        session.commit()
        attempt_id = attempt.id
    context, tab, errors = spanish_tab(chromium)
    try:
        log_in(tab, live_server, "tutor1")
        assert tab.locator('[data-field="role"]').text_content() == "tutor"
        tab.goto(f"{live_server.url}/courses/{spanish_course['course']}")
        look(tab, "tutor-course")
        tab.goto(f"{live_server.url}/assessment/exams/{spanish_course['exam']}")
        look(tab, "tutor-exam")
        tab.get_by_role("link", name="Revisión").first.click()
        tab.get_by_label("Nota nueva").wait_for()
        look(tab, "tutor-review")
        tab.get_by_label("Elemento").select_option(index=1)
        tab.get_by_label("Nota nueva").fill("0,5")  # as a Spanish tutor writes it
        tab.get_by_label("Motivo (lo ve el estudiante)").fill("La unidad faltaba, el valor era casi correcto")
        tab.get_by_role("button", name="Cambiar la nota").click()
        tab.locator(".flash--success", has_text="Nota cambiada.").wait_for()
        assert "0,5/1 puesto por el tutor" in (tab.locator(".result--changed").first.text_content() or "")
        tab.get_by_label("Comentario para el estudiante").fill("Repasa el alcance del láser en el manual.")
        tab.get_by_role("button", name="Añadir el comentario").click()
        tab.locator(".flash--success", has_text="Comentario añadido.").wait_for()
        look(tab, "tutor-corrected")

        student_context, student_tab, student_errors = spanish_tab(chromium)
        try:
            log_in(student_tab, live_server, "student1")
            student_tab.goto(f"{live_server.url}/assessment/attempts/{attempt_id}")
            comments = student_tab.locator("#comments").text_content() or ""
            assert "La unidad faltaba" in comments and "Repasa el alcance" in comments
            look(student_tab, "student-sees-correction")
        finally:
            student_context.close()
        errors += student_errors
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"


def test_the_demo_student_finds_the_demo_tests_and_survey_in_spanish(chromium, app, demo_accounts,
                                                                     live_server: LiveServer) -> None:
    """What `telelab up` seeds, read in Spanish: the Spanish demo course's quiz, timed and experimental tests and its
    survey on the Tests page, the timed test's page in Spanish, and the survey's statements in Spanish."""
    from middleware.demo_course import (
        DEMO_COURSE_ES_TITLE,
        DEMO_SURVEY_TITLE_ES,
        EXPERIMENTAL_TITLE_ES,
        QUIZ_TITLE_ES,
        TIMED_TITLE_ES,
    )
    from middleware.lab_runner import seed_demo_course, seed_spanish_demo_course

    seed_demo_course(app)
    seed_spanish_demo_course(app)
    context, tab, errors = spanish_tab(chromium)
    try:
        tab.goto(f"{live_server.url}/login")
        tab.fill("#username", "student")
        tab.fill("#password", demo_accounts["student"])
        tab.get_by_role("button", name="Iniciar sesión").click()
        tab.locator('[data-field="username"]').wait_for()
        tab.get_by_role("link", name="Pruebas").first.click()
        tab.get_by_role("heading", name=DEMO_COURSE_ES_TITLE).wait_for()
        for title in (QUIZ_TITLE_ES, TIMED_TITLE_ES, EXPERIMENTAL_TITLE_ES):
            assert tab.get_by_role("link", name=title).is_visible(), title
        survey = tab.get_by_role("link", name=re.compile(f"^{DEMO_SURVEY_TITLE_ES}"))
        assert survey.count() == 1
        survey.click()
        tab.get_by_text("El sistema era fiable").wait_for()
        look(tab, "demo-survey")
        tab.go_back()
        tab.get_by_role("link", name=TIMED_TITLE_ES).click()
        tab.get_by_role("button", name="Empezar").wait_for()
        look(tab, "demo-timed-test")
        tab.get_by_role("button", name="Empezar").click()
        tab.get_by_text("¿Por qué la estimación de la odometría se aleja").wait_for()
        look(tab, "demo-timed-attempt")
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"
