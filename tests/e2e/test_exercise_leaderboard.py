"""A course's exercise leaderboard in Chromium (issue 32): the tutor finds it closed from the class view and opens it
by keyboard; a student follows the exercise page's link to it and reads their rank, their row marked; closed again,
the student reads why they cannot see it. At desktop size in English and at a phone's (390 px) in Spanish, with
screenshots (test-artifacts/exercise-leaderboard-*.png). The graded runs are made through the exercises' services:
no robot runs here."""

from __future__ import annotations

import re
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer, add_test_account, make_course, served_lab
from tests.e2e.test_exercise_form import fits
from tests.e2e.test_lessons import log_in
from tests.e2e.test_spanish import log_in as log_in_spanish
from tests.integration.exercises.test_leaderboard import EXERCISE, FULL, HALF, submit

pytestmark = pytest.mark.e2e

SLUG = EXERCISE["slug"]
SIZES = {"desktop": {"width": 1280, "height": 800}, "phone": {"width": 390, "height": 844}}
# What a person reads, in the page's language: (locale, log in, the class view's link, the buttons, the states,
# the student's rank, their row, the closed board's refusal).
WORDS = {
    "en": ("en-GB", log_in, "Leaderboard (closed to the students)", "Open it to the students",
           "Close it to the students", "Open: the course's students see this leaderboard.",
           "Closed: only the course's tutors see it", "The course's leaderboard", "You are number 2 of 3.",
           ("2", "student1 (you)", "7.5 of 15 points (50%)"), "Your tutor has not opened this leaderboard"),
    "es": ("es-ES", log_in_spanish, "Clasificación (cerrada a los estudiantes)", "Abrirla a los estudiantes",
           "Cerrarla a los estudiantes", "Abierta: los estudiantes del curso ven esta clasificación.",
           "Cerrada: solo la ven los tutores del curso", "La clasificación del curso", "Vas en el puesto 2 de 3.",
           ("2", "student1 (tú)", "7,5 de 15 puntos (50 %)"), "Tu tutor aún no ha abierto esta clasificación"),
}


DEADLINE = datetime.now(UTC) + timedelta(days=400)


@pytest.fixture(scope="module")
def board_lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    """ROB1 (tutor1; student1..4) with the exercise as a 15-point test a week ahead: student2 full marks, student1
    half, student3 none, student4 no submission."""
    from middleware.db import session_factory
    from middleware.exercises import schemas, services
    from middleware.models import User

    with served_lab("lab-1=127.0.0.1:9", tmp_path_factory.mktemp("exercise-leaderboard")) as server:
        with session_factory(server.app)() as session:
            for name in ("student2", "student3", "student4"):
                add_test_account(session, name, "student")
            session.commit()
        course = make_course(server.app, "ROB1", {"tutor1": "tutor", "student1": "student", "student2": "student",
                                                  "student3": "student", "student4": "student"})
        now = datetime.now(UTC)
        with server.app.app_context(), session_factory(server.app)() as session:
            users = {user.username: user for user in session.query(User)}
            exercise = services.add_exercise(session, users["tutor1"], schemas.definition(EXERCISE))
            services.attach_to_course(session, users["tutor1"], course, exercise, DEADLINE, 15.0)
            for name, hours_ago, end_x_m in (("student2", 3, FULL), ("student1", 2, HALF), ("student3", 1, 0.0)):
                submit(session, users[name], exercise, now - timedelta(hours=hours_ago), end_x_m)
            session.commit()
        yield server


@pytest.mark.parametrize(("size", "language"), [("desktop", "en"), ("phone", "es")])
def test_the_tutor_opens_the_leaderboard_and_a_student_reads_their_rank(
        chromium, board_lab: LiveServer, size: str, language: str) -> None:
    (locale, log_in_as, closed_link, open_button, close_button, open_state, closed_state, student_link, rank,
     own_row, refusal) = WORDS[language]
    tabs = []

    def tab(username: str):
        context = chromium.new_context(viewport=SIZES[size], locale=locale, is_mobile=size == "phone",
                                       has_touch=size == "phone")
        page = context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        tabs.append((context, errors))
        log_in_as(page, board_lab, username)
        return page

    ARTIFACTS_DIR.mkdir(exist_ok=True)
    try:
        tutor = tab("tutor1")
        tutor.goto(f"{board_lab.url}/exercises/{SLUG}/class")
        tutor.get_by_role("link", name=closed_link).click()
        state = tutor.locator("[data-field=state]")
        state.filter(has_text=closed_state).wait_for()
        rows = tutor.locator("[data-slot=standings] tbody tr")
        assert [rows.nth(i).locator("td").first.inner_text() for i in range(rows.count())] == ["1", "2", "3"]
        assert "student2" in rows.first.inner_text()
        button = tutor.get_by_role("button", name=open_button)
        button.focus()
        tutor.keyboard.press("Enter")
        state.filter(has_text=open_state).wait_for()
        assert tutor.evaluate("document.activeElement.dataset.action") == "toggle"  # the focus stays on the button
        fits(tutor)
        tutor.screenshot(path=str(ARTIFACTS_DIR / f"exercise-leaderboard-tutor-{size}.png"), full_page=True)

        student = tab("student1")
        student.goto(f"{board_lab.url}/exercises/{SLUG}")
        student.get_by_role("link", name=student_link).click()
        student.locator("[data-field=status]").filter(has_text=rank).wait_for()
        mine = student.locator("[data-slot=standings] tr[aria-current=true] td")
        assert [cell.replace("\u00a0", " ") for cell in mine.all_inner_texts()[:3]] == list(own_row)
        assert student.locator("[data-slot=control]").is_hidden()  # a student has no button to open or close it
        # A deadline in another year says its year (next year's date is not this year's), written as the reader's
        # variant of the language writes dates: a British reader's "29 Dec 2027", not the American "Dec 29, 2027".
        terms = student.locator("[data-field=terms]").inner_text()
        assert re.search(rf"\b{DEADLINE.day} \w+\.? {DEADLINE.year}", terms), terms
        fits(student)
        student.screenshot(path=str(ARTIFACTS_DIR / f"exercise-leaderboard-student-{size}.png"), full_page=True)

        # Closed again, the student reads why they cannot see it.
        tutor.get_by_role("button", name=close_button).click()
        state.filter(has_text=closed_state).wait_for()
        student.reload()
        student.locator("[data-field=status][data-kind=closed]").filter(has_text=refusal).wait_for()
        assert student.locator("[data-slot=standings]").is_hidden()
        fits(student)
        student.screenshot(path=str(ARTIFACTS_DIR / f"exercise-leaderboard-closed-{size}.png"), full_page=True)
    finally:
        for context, _ in tabs:
            context.close()
    assert not [error for _, errors in tabs for error in errors], "JavaScript errors in the pages"
