"""A Spanish student's exercise run in Chromium set to Spanish (es-ES): the grade line says the grader's feedback in
Spanish ("… de los puntos. distancia recorrida 0,00 m (umbral 6 m: 0%); …") and the measurements' table names each
measurement and the cells in Spanish, at desktop and phone sizes (test-artifacts/spanish-exercise-graded-*.png).
The program itself stays Python, so the page is checked where the grade is read, not for every English word.
Why a run could not start reads in Spanish too: a practice robot whose start died, a robot the student does not
control."""

from __future__ import annotations

import json
import re

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_exercises import exercise_lab  # noqa: F401 - the fixture
from tests.e2e.test_spanish import DESKTOP, PHONE, log_in, spanish_tab

pytestmark = pytest.mark.e2e

STILL = "from telelab import robot\nwhile robot.tick():\n    robot.stop()\n"
PRACTICE_STATUS = re.compile(r".*/api/practice$")


def test_a_spanish_student_reads_the_graders_feedback_and_measurements_in_spanish(
        chromium, exercise_lab: LiveServer) -> None:  # noqa: F811 - the fixture
    context, tab, errors = spanish_tab(chromium)
    try:
        log_in(tab, exercise_lab, "student1")
        tab.goto(f"{exercise_lab.url}/exercises")
        tab.get_by_role("link", name="Choca y sigue").click()
        tab.get_by_role("status").filter(has_text="Python").filter(has_text="está listo").wait_for(timeout=90_000)
        tab.get_by_role("button", name="Ejecutar en mi robot de prácticas").click()
        tab.get_by_role("status").filter(has_text="Ejecutando en practice-student1").wait_for(timeout=90_000)
        tab.wait_for_timeout(1500)  # a few pose-log samples
        tab.get_by_role("button", name="Parar").click()
        grade = tab.locator("[data-field=grade]").filter(has_text="Ejecución de práctica")
        grade.wait_for(timeout=30_000)
        line = grade.inner_text()
        assert "de los puntos. distancia recorrida " in line and "(umbral 6 m:" in line, line
        assert "of the points" not in line and "bar " not in line and "cells" not in line, line
        rows = tab.locator("[data-slot=measurements] tbody tr")
        names = [rows.nth(i).locator("td").first.inner_text() for i in range(rows.count())]
        assert names == ["distancia recorrida", "casillas del suelo visitadas", "mayor tiempo atascado"], names
        assert "casillas" in rows.nth(1).inner_text() and "cells" not in rows.nth(1).inner_text()
        distance = rows.nth(0).locator("td").nth(1).inner_text()
        assert re.fullmatch(r"\d+,\d\d m", distance), f"the table writes {distance!r}, not with a decimal comma"
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        for size, viewport in (("desktop", DESKTOP), ("phone", PHONE)):
            tab.set_viewport_size(viewport)
            tab.wait_for_timeout(150)
            assert tab.evaluate("document.documentElement.lang") == "es"
            grade.scroll_into_view_if_needed()
            tab.screenshot(path=str(ARTIFACTS_DIR / f"spanish-exercise-graded-{size}.png"), full_page=True)
            overflow = tab.evaluate("document.documentElement.scrollWidth - window.innerWidth")
            assert overflow <= 1, f"the graded exercise ({size}) scrolls sideways by {overflow} px"
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"


def _start_died(route) -> None:
    """/api/practice as the farm answers once a claimed robot's start died: neither running nor starting."""
    claimed = route.request.method == "POST"
    route.fulfill(status=202 if claimed else 200, content_type="application/json",
                  body=json.dumps({"running": False, "starting": claimed, "name": None}))


def _someone_else_controls(ws) -> None:
    """The page's link (every channel's frames, "<sub> <json>") with the drive channel's ready message as the lab
    answers a driver who is not the robot's controller."""
    server = ws.connect_to_server()

    def to_page(message) -> None:
        sub, _, text = message.partition(" ") if isinstance(message, str) else ("", "", "")
        if text.startswith('{"type":"ready"'):
            ready = json.loads(text)
            if "is_controller" in ready:
                message = f"{sub} {json.dumps({**ready, 'is_controller': False})}"
        ws.send(message)

    server.on_message(to_page)


def test_a_spanish_student_reads_why_a_run_did_not_start_in_spanish(
        chromium, exercise_lab: LiveServer) -> None:  # noqa: F811 - the fixture
    context, tab, errors = spanish_tab(chromium)
    try:
        log_in(tab, exercise_lab, "student1")
        tab.route(PRACTICE_STATUS, _start_died)
        # A WebSocket route takes effect in documents loaded after it: set before the page, used by the second run.
        tab.route_web_socket("**/ws/link", _someone_else_controls)
        tab.goto(f"{exercise_lab.url}/exercises/bump-and-go")
        status = tab.get_by_role("status")
        status.filter(has_text="está listo").wait_for(timeout=90_000)
        run = tab.get_by_role("button", name="Ejecutar en mi robot de prácticas")
        run.click()
        # Said at once (the page stops waiting for a start that died), in the student's language.
        status.filter(has_text="Tu robot de prácticas no arrancó.").wait_for(timeout=10_000)
        assert run.is_enabled()

        tab.unroute(PRACTICE_STATUS)
        run.click()
        status.filter(has_text="Ahora no controlas este robot.").wait_for(timeout=90_000)
        assert run.is_enabled()
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"
