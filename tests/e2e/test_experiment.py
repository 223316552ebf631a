"""The teleoperation-under-delay experiment in Debian's Chromium against the real three tiers and a course-B robot.

A student starts a trial, drives off A with the keys in the robot's console, and watches the experiment page
follow the run as it happens; the rest of the course is travelled by placing the robot (World.set_pose in the
in-process skill server) because a real drive along the corridor would take a minute. A tutor then reads the
plot and downloads the CSV. Another student gives a trial up mid-course and has the next one recorded after
driving A -> B -> A on course A, at desktop and phone size.
"""

from __future__ import annotations

import csv
import io
import json
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from skill_server.server import create_server
from skill_server.sim.geometry import Pose2D
from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer, make_course, ready_for_trials, served_lab
from tests.e2e.test_console import log_in

pytestmark = pytest.mark.e2e
PHONE = {"width": 390, "height": 844}
DESKTOP = {"width": 1280, "height": 800}


@contextmanager
def course_lab(scene: str, robot_name: str, tmp_path: Path) -> Iterator[tuple[Any, LiveServer]]:
    """A real-time course skill server in this process (so the test can place the robot on the course) and the
    lab served with it."""
    running = create_server(port=0, scene=scene, realtime=True, robot_name=robot_name)
    try:
        with served_lab(f"{robot_name}=127.0.0.1:{running.port}", tmp_path) as server:
            yield running, server
    finally:
        running.stop(grace_s=0.5)


@pytest.fixture
def course_b_lab(tmp_path: Path) -> Iterator[tuple[Any, LiveServer]]:
    with course_lab("course-B", "course-b", tmp_path) as lab:
        make_course(lab[1].app, "EXP", {"tutor1": "tutor", "student1": "student"})  # tutor1 reads its results
        ready_for_trials(lab[1].app, "student1")
        yield lab


@pytest.fixture
def course_a_lab(tmp_path: Path) -> Iterator[tuple[Any, LiveServer]]:
    with course_lab("course-A", "course-a", tmp_path) as lab:
        ready_for_trials(lab[1].app, "student1")
        yield lab


def place(robot, x_m: float, y_m: float) -> None:
    """Puts the robot at (x, y) facing east and lets the world loop (and its course monitor) see it."""
    world = robot.world
    world.set_pose(Pose2D(x_m, y_m, 0.0))
    assert world.wait_for_snapshot(world.snapshot.tick + 5, 5.0) is not None


def run_message(page) -> str:
    return page.locator('[data-field="run-message"]').text_content() or ""


def shoot(page, name: str) -> None:
    """Screenshots the page at desktop and phone width (full page), back at desktop width after."""
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / f"{name}-desktop.png"), full_page=True)
    page.set_viewport_size(PHONE)
    page.screenshot(path=str(ARTIFACTS_DIR / f"{name}-phone.png"), full_page=True)
    page.set_viewport_size(DESKTOP)


def test_a_student_s_trial_is_followed_live_and_recorded_and_the_tutor_reads_the_plot_and_csv(
    page, chromium, course_b_lab: tuple[Any, LiveServer]
) -> None:
    course_b_robot, experiment_lab = course_b_lab
    log_in(page, experiment_lab, "student1", STUDENT_PASSWORD)
    page.get_by_role("link", name="Experiment").click()
    page.locator("#trial-robot").wait_for()
    assert page.locator("#trial-robot option").all_text_contents() == ["course-b (course-B)"]
    page.get_by_role("button", name="Start a trial").click()

    # The condition the server drew is the one the page shows, and the one recorded in the end.
    page.locator('[data-field="run"]').wait_for()
    state = json.loads(page.evaluate("fetch('/api/experiment/state').then((r) => r.text())"))
    trial = state["trial"]
    assert trial["course"] == "course-B" and trial["delay_s"] in (1.0, 3.0) and state["delay_s"] == trial["delay_s"]
    shown = page.locator('[data-field="condition"]').text_content() or ""
    assert f"{trial['delay_s']:g} s" in shown and ("on" if trial["feedback"] else "off") in shown
    page.locator('[data-field="run-message"]', has_text="drive off to start the clock").wait_for()
    assert page.locator('.experiment__step[data-state="current"]').text_content() == "Start at A"

    # Drive off A with the keys, in the robot's console the page links to.
    with page.context.expect_page() as opened:
        page.get_by_role("link", name="Open the robot's console").click()
    console = opened.value
    console.locator('[data-connection="drive"][data-phase="open"]').wait_for()
    console.locator('queue-panel[data-role="controller"]').wait_for()
    console.locator("body").focus()
    console.keyboard.down("ArrowUp")
    try:
        page.locator('[data-field="run-message"]', has_text="Run 1 under way").wait_for(timeout=8000)
    finally:
        console.keyboard.up("ArrowUp")
    assert course_b_robot.world.snapshot.ground_truth.x_m > -2.7
    assert page.locator('.experiment__step[data-state="done"]').count() == 1
    shoot(page, "experiment-trial")

    # A white line touched: the page says so and counts it while the robot goes back to A.
    place(course_b_robot, -2.0, -1.0)
    page.locator('[data-field="run-message"]', has_text="touched a white line").wait_for(timeout=3000)
    assert page.locator('[data-field="run-errors"]').text_content() == "1"
    place(course_b_robot, -2.0, -1.5)
    page.locator('[data-field="run-message"]', has_text="1 line contact so far").wait_for(timeout=3000)
    place(course_b_robot, 0.0, 0.0)
    time.sleep(0.2)
    place(course_b_robot, 3.0, 1.5)

    # Arrival at B ends the run; the page records the trial by itself with the robot's time and errors.
    page.locator('[data-field="last-trial"]').wait_for(timeout=5000)
    summary = page.locator('[data-field="last-trial"]').text_content() or ""
    assert "1 line contact." in summary and "course-B" in summary
    recorded = json.loads(page.evaluate("fetch('/api/experiment/state').then((r) => r.text())"))["last_trial"]
    assert recorded["id"] == trial["id"] and recorded["status"] == "completed" and recorded["errors"] == 1
    assert (recorded["delay_s"], recorded["feedback"]) == (trial["delay_s"], trial["feedback"])
    assert recorded["total_time_s"] > 1.0
    assert page.get_by_role("button", name="Start the next trial").is_visible()
    shoot(page, "experiment-recorded")
    console.close()

    # The tutor sees the class's result in the plot and the table, and downloads it as CSV.
    tutor_context = chromium.new_context(viewport=DESKTOP, accept_downloads=True)
    tutor = tutor_context.new_page()
    try:
        log_in(tutor, experiment_lab, "tutor1", STUDENT_PASSWORD)
        tutor.goto(f"{experiment_lab.url}/experiment")
        mean = tutor.locator('svg[data-course="course-B"] .plot__err')
        mean.wait_for(state="attached")  # one trial: its error bar has no height, so it is not "visible"
        assert float(mean.get_attribute("data-mean")) == pytest.approx(recorded["total_time_s"], abs=0.01)
        assert tutor.locator('svg[data-course="course-B"] .plot__point').count() == 1
        row = tutor.locator('[data-slot="summary"] tbody tr').first.text_content() or ""
        assert "course-B" in row and f"{trial['delay_s']:g} s" in row
        shoot(tutor, "experiment-results")
        with tutor.expect_download() as downloaded:
            tutor.get_by_role("link", name="Download CSV").click()
        rows = list(csv.DictReader(io.StringIO(Path(downloaded.value.path()).read_text())))
        assert len(rows) == 1
        assert rows[0]["username"] == "student1" and rows[0]["course"] == "course-B"
        assert rows[0]["errors"] == "1" and float(rows[0]["delay_s"]) == trial["delay_s"]
        assert rows[0]["feedback"] == ("on" if trial["feedback"] else "off")
        assert float(rows[0]["total_time_s"]) == pytest.approx(recorded["total_time_s"], abs=0.001)
    finally:
        tutor_context.close()


def drive_off_a(console, page, robot) -> None:
    """Holds the up arrow in the robot's console until the robot has left A (the robot's true pose), then waits
    for the experiment page to say a run is under way (wide margins: the machine is shared and loaded)."""
    console.locator("body").focus()
    console.keyboard.down("ArrowUp")
    try:
        deadline = time.monotonic() + 30
        while robot.world.snapshot.ground_truth.x_m < -2.0 and time.monotonic() < deadline:
            time.sleep(0.05)
    finally:
        console.keyboard.up("ArrowUp")
    assert robot.world.snapshot.ground_truth.x_m >= -2.0, "the robot never left A"
    page.locator('[data-field="run-message"]', has_text="under way").wait_for(timeout=30000)


@pytest.mark.parametrize("size", ["desktop", "phone"])
def test_after_giving_up_a_student_s_next_trial_counts_the_next_run_and_is_recorded(
    page, course_a_lab: tuple[Any, LiveServer], size: str
) -> None:
    course_a_robot, lab = course_a_lab
    viewport = DESKTOP if size == "desktop" else PHONE
    page.set_viewport_size(viewport)
    log_in(page, lab, "student1", STUDENT_PASSWORD)
    page.goto(f"{lab.url}/experiment")
    page.get_by_role("button", name="Start a trial").click()
    page.locator('[data-field="run-message"]', has_text="drive off to start the clock").wait_for()
    with page.context.expect_page() as opened:
        page.get_by_role("link", name="Open the robot's console").click()
    console = opened.value
    console.set_viewport_size(viewport)
    console.locator('queue-panel[data-role="controller"]').wait_for()

    # The first trial: off A with the keys, then given up mid-course.
    drive_off_a(console, page, course_a_robot)
    page.get_by_role("button", name="Give up this trial").click()
    page.get_by_role("button", name="Start a trial").click()

    # The next trial: the given-up run is over, so the page asks for A, not for that run to be finished.
    page.locator('[data-field="run-message"]', has_text="back to A").wait_for(timeout=30000)
    assert "began before your trial" not in run_message(page)
    assert page.locator('[data-field="run-time"]').text_content() == "0.0 s"
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / f"experiment-after-give-up-{size}.png"), full_page=True)

    # Back to A (placed: a real drive back along 5 m of course takes most of a minute), then A -> B -> A: off A
    # with the keys and, for the same reason, placed at B and back at A.
    place(course_a_robot, -2.5, 0.0)
    page.locator('[data-field="run-message"]', has_text="drive off to start the clock").wait_for(timeout=30000)
    drive_off_a(console, page, course_a_robot)
    assert "began before your trial" not in run_message(page)
    place(course_a_robot, 2.4, 0.0)
    page.locator('[data-field="run-message"]', has_text="now drive back to A").wait_for(timeout=30000)
    place(course_a_robot, -2.45, 0.0)

    page.locator('[data-field="last-trial"]').wait_for(timeout=30000)
    summary = page.locator('[data-field="last-trial"]').text_content() or ""
    assert "Trial recorded" in summary and "course-A" in summary and "0 line contacts." in summary
    assert page.get_by_role("button", name="Start the next trial").is_visible()
    state = json.loads(page.evaluate("fetch('/api/experiment/state').then((r) => r.text())"))
    assert state["trial"] is None and state["delay_s"] == 0.0
    assert state["last_trial"]["status"] == "completed" and state["last_trial"]["total_time_s"] > 0
    page.screenshot(path=str(ARTIFACTS_DIR / f"experiment-next-trial-recorded-{size}.png"), full_page=True)
    console.close()
