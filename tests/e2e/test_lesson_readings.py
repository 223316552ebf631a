"""The lesson page shows the robot's raw readings beside the video when the learner asks, by keyboard: odometry's
time plot and the sonar and laser polar plots of the robot the lesson drives, at desktop and phone sizes.
Screenshots: lesson-readings-desktop.png, lesson-readings-phone.png."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_lessons import TRACK, lesson_on_pattern, pattern_video, practice_robot_running  # noqa: F401

pytestmark = pytest.mark.e2e
READINGS = ("Odometry", "Sonar", "Laser")


def test_a_learner_shows_the_raw_readings_beside_the_video(page, live_server: LiveServer,
                                                           pattern_video: Path) -> None:  # noqa: F811
    lesson_id = lesson_on_pattern(live_server, pattern_video, TRACK, "readings", "Readings")
    with practice_robot_running(page, live_server):
        page.goto(f"{live_server.url}/lessons/{lesson_id}")
        page.get_by_role("region", name="Camera", exact=True).wait_for(timeout=30_000)
        assert all(page.get_by_role("region", name=n, exact=True).count() == 0 for n in READINGS)
        toggle = page.get_by_role("checkbox", name="Show the raw readings (odometry, sonar, laser)")
        toggle.focus()
        page.keyboard.press("Space")
        page.wait_for_url("**readings=1**")
        for name in READINGS:
            page.get_by_role("region", name=name, exact=True).wait_for(timeout=30_000)
        assert page.get_by_role("checkbox", name="Show the raw readings (odometry, sonar, laser)").is_checked()
        video_box = page.locator("video").bounding_box()
        for name in READINGS:
            box = page.get_by_role("region", name=name, exact=True).bounding_box()
            assert box["x"] >= video_box["x"] + video_box["width"], f"{name} is beside the video"
        assert page.get_by_role("img", name="Sonar readings around the robot, forward up").is_visible()
        assert page.get_by_role("img", name="Laser scan around the robot, forward up").is_visible()
        assert page.locator('[data-field="odometry-plot"]').is_visible()
        page.wait_for_function("document.querySelector('#laser-nearest-line')?.textContent.match(/\\d/)",
                               timeout=30_000)
        page.screenshot(path=str(ARTIFACTS_DIR / "lesson-readings-desktop.png"), full_page=True)
        page.set_viewport_size({"width": 390, "height": 844})
        assert page.evaluate("document.scrollingElement.scrollWidth") <= 390
        page.screenshot(path=str(ARTIFACTS_DIR / "lesson-readings-phone.png"), full_page=True)
