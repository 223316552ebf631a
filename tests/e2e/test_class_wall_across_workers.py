"""The class wall across web workers, in Chromium (issue 31): the tutor's wall is served by one worker, the students'
consoles by another, both on one PostgreSQL database (as `telelab up --workers 2` runs them). The tutor sees the
students' robots move, takes one over, and the student's console on the other worker shows the takeover banner at
once and is refused; giving the robot back, and the tutor leaving the wall, take the banner away and give the student
control again. One student is at a desk, the other on a phone."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer, _let_go, make_course, make_test_app
from tests.e2e.test_class_wall import PHONE
from tests.integration.middleware.test_events_across_workers import make_test_app_without_user

pytestmark = [pytest.mark.e2e, pytest.mark.postgres, pytest.mark.alone]
STUDENTS = ("student1", "student2")
BANNER_AT_ONCE_S = 5.0  # the click to the banner on the other worker (NOTIFY, the student's channel) on a loaded host


def _log_in(tab, server: LiveServer, username: str) -> None:
    tab.goto(f"{server.url}/login")
    tab.fill("#username", username)
    tab.fill("#password", STUDENT_PASSWORD)
    tab.get_by_role("button", name="Log in").click()
    tab.locator('[data-field="username"]').wait_for()


def test_a_takeover_on_one_worker_shows_at_once_in_the_students_console_on_another(
        page, chromium, postgres_url: str, tmp_path: Path, skill_server_address: str) -> None:
    from middleware.access.commands import robot_commands
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.teaching.practice_robots import practice_manager

    robots = f"lab-1={skill_server_address}"
    tutors_worker = make_test_app(postgres_url, robots, tmp_path / "w0")
    students_worker = make_test_app_without_user(postgres_url, robots, tmp_path / "w1")
    apps = (tutors_worker, students_worker)
    with session_factory(tutors_worker)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        session.commit()
        ids = {user.username: user.id for user in session.query(User)}
    course_id = make_course(tutors_worker, "ROB301", {"tutor1": "tutor", **dict.fromkeys(STUDENTS, "student")})
    wall_server, console_server = LiveServer(tutors_worker), LiveServer(students_worker)
    desk = chromium.new_context(viewport={"width": 1280, "height": 800})
    phone = chromium.new_context(**PHONE)
    errors: list[str] = []
    try:
        _log_in(page, wall_server, "tutor1")
        page.goto(f"{wall_server.url}/courses/{course_id}/class")
        page.get_by_role("button", name="Start the class session").click()
        page.get_by_role("status").filter(has_text="2 of 2 robots ready").wait_for(timeout=90_000)
        page.goto(f"{wall_server.url}/courses/{course_id}/class/wall")
        tiles = page.locator(".wall-tile")
        page.locator(".wall-tile[data-pose]").nth(1).wait_for(timeout=20_000)

        consoles = {}
        for name, context in zip(STUDENTS, (desk, phone), strict=True):
            tab = context.new_page()
            tab.on("pageerror", lambda error: errors.append(str(error)))
            _log_in(tab, console_server, name)
            tab.goto(f"{console_server.url}/lab/practice-{name}")
            tab.locator("#robot-online", has_text="Online").wait_for(timeout=20_000)
            consoles[name] = tab
        banner = {name: tab.locator("[data-field=takeover]") for name, tab in consoles.items()}
        assert all(not b.is_visible() for b in banner.values())

        # The students' robots move (commanded on the students' worker), and the wall on the tutor's draws them moving.
        before = [tiles.nth(i).get_attribute("data-pose") for i in range(2)]
        for name in STUDENTS:
            robot_commands(students_worker).for_user(f"practice-{name}", ids[name]).hold_drive(0.2, 0.6, 6.0)
        for i in range(2):
            tiles.nth(i).and_(page.locator("[data-state=driving]")).wait_for(timeout=10_000)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and any(tiles.nth(i).get_attribute("data-pose") == before[i]
                                                  for i in range(2)):
            page.wait_for_timeout(200)
        assert all(tiles.nth(i).get_attribute("data-pose") != before[i] for i in range(2)), before

        # Take over on the tutor's worker: the student's console on the other worker says so at once.
        clicked = time.monotonic()
        page.get_by_role("button", name="Take over: student1").click()
        banner["student1"].filter(has_text="Your tutor tutor1 has taken over this robot.").wait_for(timeout=15_000)
        shown_s = time.monotonic() - clicked
        print(f"takeover banner on the other worker {shown_s:.2f} s after the click")
        assert shown_s <= BANNER_AT_ONCE_S
        assert "Control comes back to you" in banner["student1"].inner_text()
        assert consoles["student1"].get_by_role("alert").filter(has_text="has taken over this robot").count() == 1
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        consoles["student1"].screenshot(path=str(ARTIFACTS_DIR / "console-taken-over-desktop.png"))
        student1 = robot_commands(students_worker).for_user("practice-student1", ids["student1"])
        assert not student1.is_controller()  # the student's worker refuses the student's commands now
        assert robot_commands(tutors_worker).for_user("practice-student1", ids["tutor1"]).is_controller()

        # Given back: the banner goes, the student hears control is back and drives again.
        page.get_by_role("button", name="Give back: student1").click()
        banner["student1"].wait_for(state="hidden", timeout=15_000)
        consoles["student1"].get_by_role("status").filter(has_text="You have your robot back").wait_for()
        deadline = time.monotonic() + 5  # the worker's answer of who holds a robot is at most 1 s old
        while not student1.is_controller() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert student1.is_controller()

        # The tutor leaves the wall while holding student2's robot (on a phone): it goes back at once.
        page.get_by_role("button", name="Take over: student2").click()
        banner["student2"].filter(has_text="Your tutor tutor1 has taken over this robot.").wait_for(timeout=15_000)
        width = consoles["student2"].evaluate("document.documentElement.scrollWidth")
        assert width <= PHONE["viewport"]["width"], f"the console scrolls sideways on a phone: {width} px"
        assert banner["student2"].bounding_box()["y"] < PHONE["viewport"]["height"], "the banner is off screen"
        consoles["student2"].screenshot(path=str(ARTIFACTS_DIR / "console-taken-over-phone.png"))
        page.close()
        banner["student2"].wait_for(state="hidden", timeout=15_000)
        consoles["student2"].get_by_role("status").filter(has_text="You have your robot back").wait_for()
        assert not errors, f"JavaScript errors in the students' consoles: {errors}"
    finally:
        for context in (desk, phone):
            context.close()
        practice_manager(tutors_worker).shutdown()
        for server in (wall_server, console_server):
            server.stop()
        for app in apps:
            _let_go(app)  # its ticker, links, farm and practice keeper
            session_factory(app).kw["bind"].dispose()
