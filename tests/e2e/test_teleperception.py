"""The teleperception exercise in Chromium against the real three tiers, at desktop and phone width: a student opens
it from the console, sees the evidence grid drawn and its readings counted, switches a layer off, and downloads
the readings as CSV."""

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
