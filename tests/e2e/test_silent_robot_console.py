"""A robot that does not answer cannot describe its panels (RobotInfo): its console still opens, with the
middleware's own panels (driving, the turn, chat, response times) and a line saying why the rest is missing."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_panels import open_console

pytestmark = pytest.mark.e2e


@pytest.mark.parametrize(("width", "height"), [(1280, 800), (390, 844)], ids=["desktop", "phone"])
def test_a_silent_robot_s_console_says_why_its_camera_and_sensors_are_missing(
        page, live_server: LiveServer, width: int, height: int) -> None:
    page.set_viewport_size({"width": width, "height": height})
    open_console(page, live_server, robot="ghost", online=False)
    line = page.locator("#console-error")
    line.filter(has_text="does not answer").wait_for()
    assert "camera, sensors and skills cannot be listed" in (line.text_content() or "")
    assert line.is_visible()
    page.locator("drive-pad").wait_for()
    assert page.locator("queue-panel").count() == 1
    assert page.locator("camera-panel").count() == 0 and page.locator("sonar-panel").count() == 0
    kinds = page.eval_on_selector_all(".panel-frame", "frames => frames.map((f) => f.dataset.panelId)")
    assert sorted(kinds) == ["chat", "drive", "queue", "response-times"]
    page.screenshot(path=str(ARTIFACTS_DIR / f"console-silent-robot-{width}.png"))
