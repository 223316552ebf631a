"""Robot pools in Chromium: a student on a phone queues for "any sim robot" from the robots page, reads their place
and expected wait, and lands in the console of the first robot whose turn ends; an admin reads every pool's robots,
their controllers and health on the pools page."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer, served_lab
from tests.e2e.test_lessons import log_in

pytestmark = [pytest.mark.e2e, pytest.mark.alone]  # the turn of 8 s must not pass while a page loads


@pytest.fixture
def pool_lab(tmp_path, skill_server_address: str) -> Iterator[LiveServer]:
    from middleware.robots.processes import SkillServerProcess, wait_until_serving

    second = SkillServerProcess("sim-2", "lab")
    second.start()
    try:
        wait_until_serving(second.address)
        with served_lab(f"sim-1={skill_server_address},sim-2={second.address}", tmp_path) as server:
            server.app.config["DEFAULT_TURN_LENGTH_S"] = 8.0
            server.app.config["ACCESS_GRACE_S"] = 60.0
            yield server
    finally:
        second.stop()


def test_a_student_waits_for_any_robot_of_a_kind_and_an_admin_reads_the_pools(page, chromium,
                                                                               pool_lab: LiveServer) -> None:
    from middleware.access.coordinator import access_coordinator
    from middleware.access.pool_seats import pool_seats_of
    from middleware.auth.services import create_user, find_user
    from middleware.db import session_factory

    app = pool_lab.app
    with session_factory(app)() as session:
        for name, role in (("bob", "student"), ("cy", "student"), ("root", "admin")):
            create_user(session, name, role, STUDENT_PASSWORD)
        session.commit()
        bob, cy = find_user(session, "bob").id, find_user(session, "cy").id
    with pool_seats_of(access_coordinator(app)) as seats:
        bobs_robot = seats.claim("sim", bob).robot_name
        taken = {bobs_robot, seats.claim("sim", cy).robot_name}
    assert taken == {"sim-1", "sim-2"}
    bobs_desk = chromium.new_context(viewport={"width": 1280, "height": 900})
    bobs_console = bobs_desk.new_page()
    log_in(bobs_console, pool_lab, "bob")
    bobs_console.goto(f"{pool_lab.url}/lab/{bobs_robot}")
    turn = bobs_console.locator("queue-panel")
    turn.locator('[data-field="queue-summary"]', has_text="Nobody is waiting").wait_for(timeout=30_000)

    phone = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    student = phone.new_page()
    try:
        log_in(student, pool_lab, "student1")
        student.goto(f"{pool_lab.url}/lab")
        student.get_by_role("link", name="Queue for any sim robot (2 robots)").click()
        student.get_by_role("status").filter(has_text="You are number 1 of 1 waiting for a sim robot.").wait_for()
        # Bob's turn is now limited by the pool's waiter, and his turn panel counts them among those waiting.
        turn.locator('[data-field="queue-summary"]', has_text="Others are waiting for a robot of this kind").wait_for()
        assert turn.locator('[data-field="queue-size"]').inner_text() == "1"
        assert turn.get_by_role("button", name="Pass the turn").is_visible()
        turn.screenshot(path=str(ARTIFACTS_DIR / "pool-waiter-controller-turn.png"))
        assert "robots serve this queue" in student.locator("[data-field=wait]").inner_text()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        student.screenshot(path=str(ARTIFACTS_DIR / "pool-waiting-phone.png"), full_page=True)
        student.wait_for_url("**/lab/sim-*", timeout=30_000)
        student.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30_000)
        robot = student.url.rsplit("/", 1)[1]
        assert robot in taken

        log_in(page, pool_lab, "root")
        page.goto(f"{pool_lab.url}/admin/pools")
        pool = page.locator('[data-pool="sim"]')
        assert "2 robot(s)" in pool.locator("[data-field=summary]").inner_text()
        row = pool.locator(f'tr[data-robot="{robot}"]')
        assert "student1" in row.inner_text() and row.locator("[data-field=health]").inner_text() == "Ready"
        page.screenshot(path=str(ARTIFACTS_DIR / "pools-admin.png"), full_page=True)
    finally:
        phone.close()
        bobs_desk.close()
