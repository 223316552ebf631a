"""The teleperception exercise in Chromium against the real three tiers, at desktop and phone width: a student opens
it from the console, sees the evidence grid drawn and its readings counted, switches a layer off, and downloads
the readings as CSV; and, in an obstacle-zone test, marks the obstacles on the grid and is graded on the marks."""

from __future__ import annotations

import csv
import io
import re

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_panels import open_console, wait_for

pytestmark = pytest.mark.e2e

DRAWN_PIXELS = """(canvas) => {
  const data = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
  let drawn = 0;
  for (let i = 3; i < data.length; i += 4) if (data[i] > 0) drawn += 1;
  return drawn;
}"""


def counts(page) -> dict[str, int]:
    text = page.locator('[data-field="counts"]').text_content() or ""
    found = re.search(r"sonar (\d+), laser (\d+) \(standing (\d+), moving (\d+)\)", text)
    return dict(zip(("sonar", "laser", "static", "moving"), map(int, found.groups()), strict=True)) if found else {}


@pytest.mark.parametrize(("width", "height"), [(1280, 800), (390, 844)], ids=["desktop", "phone"])
def test_a_student_opens_the_exercise_sees_the_grid_and_downloads_the_readings(
        page, live_server: LiveServer, width: int, height: int) -> None:
    page.set_viewport_size({"width": width, "height": height})
    open_console(page, live_server, "student1")
    page.get_by_test_id("teleperception-link").click()
    page.wait_for_url("**/lab/lab-1/teleperception")
    page.get_by_role("heading", name="Part 1: without motion").wait_for()
    page.get_by_role("heading", name="Part 2: with motion").wait_for()
    canvas = page.get_by_test_id("evidence-canvas")
    canvas.wait_for()
    wait_for(lambda: counts(page).get("sonar", 0) >= 3, 20, "the page never counted sonar readings")
    drawn = canvas.evaluate(DRAWN_PIXELS)
    box = canvas.bounding_box()
    assert box is not None and box["width"] <= width and drawn > 0.02 * box["width"] * box["height"], drawn
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / f"teleperception-{width}.png"), full_page=True)

    # Only the laser: the sonar ring's cones behind the robot leave the picture.
    page.get_by_label("Sonar", exact=True).uncheck()
    wait_for(lambda: canvas.evaluate(DRAWN_PIXELS) < drawn, 10, "switching the sonar layer off changed nothing")

    with page.expect_download() as downloading:
        page.get_by_role("link", name="Export readings (CSV)").click()
    download = downloading.value
    assert download.suggested_filename == "teleperception-lab-1.csv"
    with open(download.path(), encoding="utf-8") as file:
        rows = list(csv.DictReader(io.StringIO(file.read())))
    assert rows and {"sonar", "laser"} == {row["sensor"] for row in rows}
    assert {"odom_x_m", "odom_y_m", "odom_theta_rad", "angle_rad", "range_m", "capture_unix_s"} <= set(rows[0])
    assert page.locator('[data-field="error"]').is_hidden()


@pytest.mark.parametrize(("width", "height"), [(1280, 800), (390, 844)], ids=["desktop", "phone"])
def test_the_exercise_takes_a_turn_itself_and_its_buttons_drive_the_robot(
        page, live_server: LiveServer, width: int, height: int) -> None:
    """Issue 34, item 16: opened straight from a link, with nobody in control, "Turn in place" was refused as
    "someone else has control"; the page shows the Turn panel, takes the free robot and the button turns it."""
    from tests.e2e.test_panels import STUDENT_PASSWORD

    page.set_viewport_size({"width": width, "height": height})
    page.goto(f"{live_server.url}/login")
    page.fill("#username", "student1")
    page.fill("#password", STUDENT_PASSWORD)
    page.get_by_role("button", name="Log in").click()
    page.locator('[data-field="username"]').first.wait_for(state="attached")
    page.goto(f"{live_server.url}/lab/lab-1/teleperception")
    turn = page.get_by_role("region", name="Turn")
    turn.get_by_text("You have control").wait_for(timeout=20_000)
    page.get_by_role("button", name="Turn in place (4 s)").click()
    page.locator('[data-field="message"]').filter(has_text="Moving: these readings go to part 2.").wait_for()
    assert page.locator('[data-field="error"]').is_hidden(), page.locator('[data-field="error"]').text_content()
    wait_for(lambda: counts(page).get("moving", 0) > 0, 15, "no readings were taken while the robot turned")
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / f"teleperception-turn-{width}.png"), full_page=True)


OBSTACLES = [(2.2, 1.1, 2.8, 1.7), (-2.6, 1.35, -1.8, 1.85), (-1.6, -2.25, -0.4, -1.75), (1.55, -1.75, 2.05, -1.25)]


def css_point(canvas, x_m: float, y_m: float) -> tuple[float, float]:
    """Where a lab-frame point is drawn on the canvas (the grid spans the room and 0.5 m around it)."""
    box = canvas.bounding_box()
    return box["x"] + (x_m + 4.5) / 9.0 * box["width"], box["y"] + (3.5 - y_m) / 7.0 * box["height"]


def obstacle_zone_exam(live_server: LiveServer) -> int:
    """An obstacle-zone test on lab-1, open now, set by tutor1 for a course of student1; its id."""
    from datetime import UTC, datetime, timedelta

    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from tests.conftest import STUDENT_PASSWORD, LabClient, make_course
    from tests.integration.bookings.conftest import api

    with session_factory(live_server.app)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        session.commit()
    course_id = make_course(live_server.app, "TP1", {"tutor1": "tutor", "student1": "student"})
    tutor = LabClient(live_server.url)
    assert tutor.login("tutor1", STUDENT_PASSWORD) == 302
    now = datetime.now(UTC)
    status, created = api(tutor, "POST", f"/api/courses/{course_id}/exams", {
        "title": "Where are the obstacles?", "kind": "experimental", "task_kind": "obstacle_zone",
        "opens_at": (now - timedelta(minutes=1)).isoformat(), "closes_at": (now + timedelta(hours=1)).isoformat(),
        "duration_s": 900, "task_points": 10, "robot_name": "lab-1"})
    assert status == 201, created
    return int(created["exam"]["id"])


def test_a_student_marks_the_obstacle_zone_on_the_grid_and_is_graded_on_it(page, live_server: LiveServer) -> None:
    exam_id = obstacle_zone_exam(live_server)
    open_console(page, live_server, "student1")  # the drive socket gives the student the robot
    attempt = page.evaluate("""(examId) => fetch(`/api/exams/${examId}/attempts`, {method: "POST", headers: {
        "X-CSRFToken": document.querySelector('meta[name="csrf-token"]').content}}).then((r) => r.json())""",
                            exam_id)["attempt"]
    page.goto(f"{live_server.url}/assessment/attempts/{attempt['id']}")
    page.get_by_test_id("zone-exercise-link").click()
    page.wait_for_url(re.compile(r".*/lab/lab-1/teleperception\?attempt=\d+"))
    zone = page.get_by_role("region", name="Mark the obstacle zone")
    zone.wait_for()
    canvas = page.get_by_test_id("evidence-canvas")
    page.locator('[data-testid="evidence-canvas"][data-drawn]').wait_for()
    for x0, y0, x1, y1 in OBSTACLES:
        page.mouse.move(*css_point(canvas, x0, y1))
        page.mouse.down()
        page.mouse.move(*css_point(canvas, (x0 + x1) / 2, (y0 + y1) / 2), steps=3)
        page.mouse.move(*css_point(canvas, x1, y0), steps=3)
        page.mouse.up()
    zone.get_by_text("4 rectangle(s) marked.").wait_for()
    zone.get_by_role("button", name="Save my marks").click()
    page.get_by_text("Saved 4 rectangle(s).").wait_for()

    page.goto(f"{live_server.url}/assessment/attempts/{attempt['id']}")
    page.get_by_text("4 rectangle(s) marked.").wait_for()
    page.locator("#submit").click()
    score = page.locator("#score")
    score.wait_for()
    assert "10" in (score.text_content() or ""), score.text_content()
    page.get_by_text(re.compile(r"IoU 0\.[89]\d|IoU 1\.00")).wait_for()
