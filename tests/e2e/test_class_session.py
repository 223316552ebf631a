"""A class session in Chromium: the tutor starts it from the course page and watches every robot become ready;
a student (on a phone) opens their own robot from the class page, stops it on the practice page and the tutor's page
says so (issue 34, item 7: it said "ready" and the student's link led to a 404) until the student starts it again;
the tutor ends it and the student sees so."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer, make_course
from tests.e2e.test_lessons import log_in

pytestmark = pytest.mark.e2e


def test_a_tutor_runs_a_class_session_and_a_student_opens_their_robot(page, chromium, live_server: LiveServer) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.teaching.practice_robots import practice_manager

    with session_factory(live_server.app)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        create_user(session, "student3", "student", STUDENT_PASSWORD)
        session.commit()
    course_id = make_course(live_server.app, "ROB101", {"tutor1": "tutor", "student1": "student",
                                                        "student2": "student", "student3": "student"})
    phone = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    student = phone.new_page()
    try:
        log_in(page, live_server, "tutor1")
        page.goto(f"{live_server.url}/courses/{course_id}")
        page.get_by_role("link", name="Class session").click()
        page.get_by_role("status").filter(has_text="No class session is open for this course.").wait_for()
        scene = page.get_by_label("The students' robots run")
        assert scene.input_value() == "lab" and scene.locator("option").count() == 3
        page.get_by_role("button", name="Start the class session").click()
        page.get_by_role("status").filter(has_text="Class session open (lab): 3 of 3 robots ready.").wait_for(
            timeout=60_000)
        rows = page.locator("table.class-seats tbody tr")
        assert rows.count() == 3
        assert rows.nth(0).inner_text().split() == ["student1", "practice-student1", "ready", "not", "measured", "yet"]
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "class-session-tutor.png"), full_page=True)

        log_in(student, live_server, "student1")
        student.goto(f"{live_server.url}/teaching")
        student.get_by_role("link", name="My robot in class").click()
        student.get_by_role("status").filter(
            has_text="Class session of ROB101 · Course ROB101: your robot practice-student1 is ready.").wait_for()
        student.screenshot(path=str(ARTIFACTS_DIR / "class-session-student-phone.png"), full_page=True)
        student.get_by_role("link", name="Open my robot in the console").click()
        student.wait_for_url("**/lab/practice-student1")
        student.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30_000)

        student.goto(f"{live_server.url}/practice")  # the student stops their robot mid-class
        student.get_by_role("button", name="Stop it").click()
        student.get_by_role("button", name="Start my practice robot").wait_for()
        page.get_by_role("status").filter(
            has_text="Class session open (lab): 2 of 3 robots ready, 1 stopped.").wait_for(timeout=15_000)
        assert rows.nth(0).inner_text().split()[:3] == ["student1", "practice-student1", "stopped:"]
        assert "ready" in rows.nth(1).inner_text() and "ready" in rows.nth(2).inner_text()
        page.screenshot(path=str(ARTIFACTS_DIR / "class-session-tutor-stopped.png"), full_page=True)
        student.goto(f"{live_server.url}/class")
        student.get_by_role("status").filter(has_text="your robot practice-student1 is stopped").wait_for()
        assert not student.get_by_role("link", name="Open my robot in the console").is_visible()
        student.screenshot(path=str(ARTIFACTS_DIR / "class-session-student-stopped-phone.png"), full_page=True)
        student.get_by_role("button", name="Start my robot again").click()
        student.get_by_role("status").filter(has_text="your robot practice-student1 is ready").wait_for(timeout=60_000)
        page.get_by_role("status").filter(has_text="Class session open (lab): 3 of 3 robots ready.").wait_for(
            timeout=15_000)
        student.get_by_role("link", name="Open my robot in the console").click()
        student.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30_000)
        student.goto(f"{live_server.url}/class")

        page.once("dialog", lambda dialog: dialog.accept())
        page.get_by_role("button", name="End the session and stop every robot").click()
        page.get_by_role("status").filter(has_text="No class session is open for this course.").wait_for()
        student.get_by_role("status").filter(has_text="No class session is open for your courses now").wait_for(
            timeout=15_000)
        assert practice_manager(live_server.app).count() == 0
    finally:
        phone.close()
        practice_manager(live_server.app).shutdown()
