"""A tutor reads a student's response times in the class view, the same figures as the student's own console panel
shows after the student activated skills and drove their class robot (in Chromium, both of them)."""

from __future__ import annotations

import re

import pytest

from benchmarks.response_times import activate_and_drive, shown_table
from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer, make_course
from tests.e2e.test_lessons import log_in
from tests.e2e.test_panels import show_tab_of

pytestmark = pytest.mark.e2e
REPORT_WAIT_MS = 30_000  # the console reports every 10 s; the tutor's page reads every 5 s


def test_a_tutor_sees_each_student_s_response_times_as_the_student_s_panel_shows_them(
    page, chromium, live_server: LiveServer
) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory

    with session_factory(live_server.app)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        session.commit()
    course_id = make_course(live_server.app, "ROB101", {"tutor1": "tutor", "student1": "student",
                                                        "student2": "student"})
    context = chromium.new_context(viewport={"width": 1280, "height": 900})
    student = context.new_page()
    try:
        log_in(page, live_server, "tutor1")
        page.goto(f"{live_server.url}/courses/{course_id}/class")
        page.get_by_role("button", name="Start the class session").click()
        page.get_by_role("status").filter(has_text="Class session open (lab): 2 of 2 robots ready.").wait_for(
            timeout=60_000)

        log_in(student, live_server, "student1")
        student.goto(f"{live_server.url}/lab/practice-student1")
        student.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30_000)
        student.locator('odometry-panel [data-field="heading-rad"]').filter(has_text=".").wait_for()
        activate_and_drive(student, 2, drive_s=1.0)
        show_tab_of(student, "response-times")

        row = page.locator("table.class-seats tbody tr").filter(has_text="student1")
        line = row.locator('[data-field="rtt-skill-line"]')
        line.filter(has_text="2 skill activations").wait_for(timeout=REPORT_WAIT_MS)
        drive_line = row.locator('[data-field="rtt-drive-line"]')
        drive_line.filter(has_text=re.compile(r"\d+ drive commands")).wait_for(timeout=REPORT_WAIT_MS)
        page.wait_for_timeout(11_000)  # the next report carries every command the panel has timed by now
        student_sees = shown_table(student)
        tutor_text = line.text_content()
        total = student_sees["skill"]["total"]
        assert tutor_text == (f"2 skill activations: {total['min']:.1f}–{total['max']:.1f} ms, "
                              f"mean {total['mean']:.1f}, jitter {total['jitter']:.1f}"), (tutor_text, total)
        row.get_by_text("Legs").click()
        for leg in ("client", "robot"):
            for figure in ("min", "mean", "max", "jitter"):
                cell = row.locator(f'[data-field="rtt-skill-{leg}-{figure}"]').text_content()
                assert float(cell) == pytest.approx(student_sees["skill"][leg][figure], abs=0.051), (leg, figure)
        other = page.locator("table.class-seats tbody tr").filter(has_text="student2")
        assert "not measured yet" in other.inner_text()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "class-response-times-tutor.png"), full_page=True)
        page.set_viewport_size({"width": 390, "height": 844})
        row.locator('[data-field="rtt-skill-robot-max"]').scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / "class-response-times-tutor-phone.png"), full_page=True)
        wide = page.evaluate("""() => [...document.querySelectorAll('body *')]
            .filter((e) => e.getBoundingClientRect().right > 391)
            .map((e) => `${e.tagName}.${e.className}[${e.dataset.field ?? ''}] `
                + `${Math.round(e.getBoundingClientRect().right)}`)
            .slice(0, 6)""")
        assert page.evaluate("document.documentElement.scrollWidth") <= 390, f"the class view scrolls sideways: {wide}"
        page.screenshot(path=str(ARTIFACTS_DIR / "class-response-times-tutor-phone.png"), full_page=True)
    finally:
        context.close()
