"""A learner's practice robot in the full lab console, in Chromium: opened from the practice page, its
panels show live data and its owner has control; and a tutor uploads a lesson video through the editor."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_lessons import log_in
from tests.e2e.test_panels import odometry, show_tab_of, wait_for

pytestmark = pytest.mark.e2e


def test_the_owner_opens_the_practice_console_and_its_panels_show_live_data(page, live_server: LiveServer) -> None:
    from middleware.teaching.practice_robots import practice_manager

    log_in(page, live_server)
    page.goto(f"{live_server.url}/practice")
    try:
        page.get_by_role("button", name="Start my practice robot").click()
        page.locator("#practice").filter(has_text="Your practice robot practice-student1 is running").wait_for(
            timeout=30_000)  # the farm starts it once the claim is committed; the page follows it until it runs
        assert page.locator("#practice[data-running=true][data-starting=false]").count() == 1
        assert page.get_by_role("button", name="Start my practice robot").is_hidden()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "practice-running.png"), full_page=True)
        page.get_by_role("link", name="Open in the console").click()
        page.wait_for_url("**/lab/practice-student1")
        page.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30_000)
        page.locator('queue-panel[data-role="controller"]').wait_for(timeout=30_000)
        wait_for(lambda: not math.isnan(odometry(page, "x")), 15, "the practice robot's odometry shows no numbers")
        assert page.get_by_role("region", name="Camera", exact=True).count() == 1
        show_tab_of(page, "laser")
        page.locator('laser-panel [data-field="laser-nearest"]').filter(has_text=" m").wait_for()
        page.locator('skill-panel[data-skill="go_to_goal"] button[data-action="activate"]').wait_for(state="attached")
    finally:
        practice_manager(live_server.app).shutdown()


def test_the_practice_page_follows_a_starting_robot_until_it_runs(chromium, live_server: LiveServer) -> None:
    """A robot claimed and not started yet (its start runs after the claim's commit) reads as starting, with no
    start button, at phone size; the page follows it and reads it running once the farm started it."""
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.teaching.practice_robots import practice_manager

    manager = practice_manager(live_server.app)
    with session_factory(live_server.app)() as session, session.begin():
        user_id = session.query(User.id).filter(User.username == "student1").scalar()
        pending = manager.begin_start(session, user_id, "student1")
    assert pending is not None
    phone = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    page = phone.new_page()
    try:
        log_in(page, live_server)
        page.goto(f"{live_server.url}/practice")
        page.get_by_role("status").filter(has_text="Your practice robot is starting…").wait_for()
        assert page.get_by_role("button", name="Start my practice robot").is_hidden()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "practice-starting-phone.png"), full_page=True)
        pending.run()
        page.get_by_role("status").filter(has_text="Your practice robot practice-student1 is running").wait_for(
            timeout=10_000)
        page.get_by_role("button", name="Stop it").wait_for()
    finally:
        phone.close()
        manager.shutdown()


def test_a_tutor_uploads_a_video_from_the_lesson_editor(page, live_server: LiveServer, tmp_path: Path) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from tests.conftest import STUDENT_PASSWORD

    with session_factory(live_server.app)() as session:
        create_user(session, "tutor9", "tutor", STUDENT_PASSWORD)
        session.commit()
    clip = tmp_path / "My clip.webm"
    clip.write_bytes(b"\x1a\x45\xdf\xa3" + bytes(1000))
    log_in(page, live_server, "tutor9")
    page.goto(f"{live_server.url}/lessons/new")
    page.locator("#video-upload input[type=file]").set_input_files(str(clip))
    page.locator("#video-upload").get_by_role("button", name="Upload", exact=True).click()
    page.locator(".flash--success").filter(has_text="Uploaded as upload-").wait_for()
    chosen = page.locator("select[name=video_name]").input_value()
    assert chosen.startswith("upload-") and chosen.endswith(".webm")
    assert (Path(live_server.app.instance_path) / "lessons" / chosen).is_file()
