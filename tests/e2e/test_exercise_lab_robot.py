"""Submitting an exercise on a lab robot in the student's turn, in Chromium: a student who holds lab-1's turn (taken in
its console) submits on it from the exercise page and reads the grade and the trace; a student without the turn is
told who drives and how to get one (the robot's console, its queue), not shown a button that would be refused; and
a turn lost during the run ends the run at once, saying so, and the run is graded. Desktop and phone."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer, served_lab
from tests.e2e.test_exercises import set_code, truth_speed, wait_until
from tests.e2e.test_lessons import log_in

pytestmark = pytest.mark.e2e

SHORT_DRIVE = "from telelab import robot\nwhile robot.tick() and robot.time() < 3:\n    robot.set_velocity(0.25, 0.0)\n"
SLOW_FOREVER = """from telelab import robot
print("driving slowly until the time is up")
while robot.tick():
    robot.set_velocity(0.05, 0.3)
"""
SIZES = {"desktop": {"width": 1280, "height": 900}, "phone": {"width": 390, "height": 844}}


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory, skill_server_address: str) -> Iterator[LiveServer]:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.teaching.practice_robots import practice_manager

    with served_lab(f"lab-1={skill_server_address}", tmp_path_factory.mktemp("exercise-lab")) as server:
        server.app.config.update(ACCESS_TICK_S=0.2)
        with session_factory(server.app)() as session:
            create_user(session, "student2", "student", STUDENT_PASSWORD)
            session.commit()
        try:
            yield server
        finally:
            practice_manager(server.app).shutdown()


def new_page(chromium, size: str):
    context = chromium.new_context(viewport=SIZES[size], is_mobile=size == "phone", has_touch=size == "phone")
    return context, context.new_page()


def hold_the_turn(page, server: LiveServer, username: str) -> None:
    """username opens lab-1's console, which joins its queue; with nobody else there, the turn is theirs."""
    log_in(page, server, username)
    page.goto(f"{server.url}/lab/lab-1")
    page.locator('queue-panel[data-role="controller"]').wait_for(timeout=30_000)


def open_exercise(page, server: LiveServer, slug: str = "bump-and-go") -> None:
    page.goto(f"{server.url}/exercises/{slug}")
    page.get_by_role("status").filter(has_text="is ready").wait_for(timeout=120_000)


def leave_lab_1(page) -> None:
    """The page leaves lab-1's queue (the next test starts with a free robot)."""
    leave = page.get_by_role("button", name="Leave lab-1's queue")
    if leave.is_visible():
        leave.click()
        page.locator('[data-slot=lab][data-turn="none"]').wait_for()


@pytest.mark.parametrize("size", ["desktop", "phone"])
def test_a_student_in_their_turn_on_lab_1_submits_on_it_and_reads_the_grade_and_the_trace(
        chromium, lab: LiveServer, size: str) -> None:
    context, page = new_page(chromium, size)
    try:
        hold_the_turn(page, lab, "student1")
        open_exercise(page, lab)
        section = page.locator("[data-slot=lab]")
        # The page lists the lab's robots and offers the turn; it joins a queue only when asked.
        page.get_by_role("button", name="Take a turn on lab-1").click()
        submit = page.get_by_role("button", name="Submit on lab-1")
        submit.wait_for(timeout=15_000)
        assert "You have control" in section.inner_text()
        assert section.get_attribute("data-turn") == "controller"
        set_code(page, SHORT_DRIVE)
        submit.click()
        page.get_by_role("status").filter(has_text="Running on lab-1").wait_for(timeout=60_000)
        wait_until(lambda: truth_speed(lab, "lab-1") > 0.1, 15, "lab-1 did not move")
        grade = page.locator("[data-field=grade]").filter(has_text="Submission")
        grade.wait_for(timeout=90_000)
        assert "%" in grade.inner_text()
        assert page.locator("[data-slot=measurements] tbody tr").count() == 3
        # The trace is drawn: the canvas has the path's blue pixels (nothing else on the map is blue). Its edges are
        # antialiased and a short run's path is partly under the start and end marks, so the colour is matched
        # loosely and a few pixels suffice (a loaded run counted 19 exact ones).
        blue = page.locator("[data-slot=map]").evaluate("""canvas => {
            const data = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
            let count = 0;
            for (let i = 0; i < data.length; i += 4) {
                const near = Math.abs(data[i] - 0x1d) + Math.abs(data[i + 1] - 0x5f) + Math.abs(data[i + 2] - 0xc4);
                if (data[i + 3] > 0 && near < 40) count++;
            }
            return count; }""")
        assert blue > 10, blue
        runs = page.locator("[data-slot=runs] li").all_inner_texts()
        assert any("submission" in run for run in runs), runs
        assert page.evaluate("document.documentElement.scrollWidth") <= SIZES[size]["width"]
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.locator("[data-slot=lab]").scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / f"exercise-lab-submitted-{size}.png"), full_page=True)
        leave_lab_1(page)
    finally:
        context.close()


@pytest.mark.parametrize("size", ["desktop", "phone"])
def test_a_student_without_the_turn_is_told_who_drives_and_how_to_get_a_turn(
        chromium, lab: LiveServer, size: str) -> None:
    holder_context, holder = new_page(chromium, "desktop")
    context, page = new_page(chromium, size)
    try:
        hold_the_turn(holder, lab, "student2")
        log_in(page, lab, "student1")
        page.goto(f"{lab.url}/exercises/bump-and-go")
        section = page.locator("[data-slot=lab]")
        # Before asking: how to get a turn, here or in the console, with the console a link away.
        take = page.get_by_role("button", name="Take a turn on lab-1")
        take.wait_for(timeout=15_000)
        assert "during your turn" in section.inner_text()
        console = page.get_by_role("link", name="Open lab-1's console (its queue and turn)")
        assert console.get_attribute("href") == "/lab/lab-1"
        page.get_by_role("status").filter(has_text="is ready").wait_for(timeout=120_000)
        take.click()
        section.filter(has_text="student2 is driving").wait_for(timeout=15_000)
        text = section.inner_text()
        assert "You are next" in text and "once your turn comes" in text, text
        assert page.get_by_role("button", name="Submit on lab-1").is_hidden()
        assert section.get_attribute("data-turn") == "waiting"
        assert page.evaluate("document.documentElement.scrollWidth") <= SIZES[size]["width"]
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        section.scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / f"exercise-lab-no-turn-{size}.png"), full_page=True)
        leave_lab_1(page)
        holder.get_by_role("button", name="Leave the queue").click()  # lab-1 is free for the next test
    finally:
        context.close()
        holder_context.close()


def test_a_turn_lost_during_a_run_ends_the_run_at_once_saying_so_and_it_is_graded(
        chromium, lab: LiveServer) -> None:
    # A submission keeps its controller's turn while it runs (access/graded_runs.py: not even Pass the turn gives it
    # away): the turn moves on mid-run only when the student leaves the queue elsewhere (here: in lab-1's console, in
    # another tab) or is dropped from it.
    context, console_tab = new_page(chromium, "desktop")
    other_context, other = new_page(chromium, "phone")
    page = context.new_page()
    try:
        hold_the_turn(console_tab, lab, "student1")
        open_exercise(page, lab)
        page.get_by_role("button", name="Take a turn on lab-1").click()
        submit = page.get_by_role("button", name="Submit on lab-1")
        submit.wait_for(timeout=15_000)
        set_code(page, SLOW_FOREVER)
        log_in(other, lab, "student2")
        other.goto(f"{lab.url}/lab/lab-1")
        other.locator('queue-panel[data-role="waiting"]').wait_for(timeout=30_000)
        submit.click()
        page.get_by_role("status").filter(has_text="Running on lab-1").wait_for(timeout=60_000)
        page.locator("[data-field=console]").filter(has_text="driving slowly").wait_for(timeout=15_000)
        # Passing is refused while the submission runs (it keeps the turn); leaving the queue is not.
        console_tab.bring_to_front()
        console_tab.get_by_role("button", name="Leave the queue").click()
        passed_at = time.monotonic()
        page.bring_to_front()
        console = page.locator("[data-field=console]")
        console.filter(has_text="The run ended").wait_for(timeout=15_000)
        assert time.monotonic() - passed_at < 10, "the run went on long after the turn had passed"
        assert "turn" in console.inner_text()
        grade = page.locator("[data-field=grade]").filter(has_text="Submission")
        grade.wait_for(timeout=30_000)
        status = page.locator("[data-field=status]")
        assert "The run ended" in status.inner_text() and "graded below" in status.inner_text(), status.inner_text()
        other.locator('queue-panel[data-role="controller"]').wait_for(timeout=10_000)
        # The page is ready again: no run hangs on, Submit on lab-1 is gone with the turn; it says who has it and
        # offers the turn again.
        assert page.get_by_role("button", name="Run on my practice robot").is_enabled()
        assert page.get_by_role("button", name="Submit on lab-1").is_hidden()
        page.locator("[data-slot=lab]").filter(
            has_text="You have no place in lab-1's queue now (student2 is driving)").wait_for(timeout=10_000)
        assert page.get_by_role("button", name="Take a turn on lab-1").is_enabled()
        wait_until(lambda: truth_speed(lab, "lab-1") < 0.02, 5, "lab-1 kept moving after the run ended")
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "exercise-lab-turn-ended.png"), full_page=True)
        leave_lab_1(page)
    except Exception:
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "exercise-lab-turn-ended-failed.png"), full_page=True)
        raise
    finally:
        other_context.close()
        context.close()
