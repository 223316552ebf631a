"""The room camera (the 2003 lab's pan-tilt-zoom camera on the wall) in Debian's Chromium: the console draws the
robot as the room's camera sees it, where it truly stands; a viewer pans, tilts and zooms their own view with the
buttons and the keyboard within the mount's limits; on a phone the view is fixed."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_panels import open_console, show_tab_of, wait_for

pytestmark = pytest.mark.e2e


def aim(page) -> tuple[float, float, float]:
    pan, tilt, hfov = (float(v) for v in (page.locator("room-camera").get_attribute("data-aim") or "").split())
    return pan, tilt, hfov


def test_a_viewer_pans_tilts_and_zooms_the_room_camera_and_a_phone_shows_it_fixed(
        page, live_server: LiveServer) -> None:
    open_console(page, live_server)
    show_tab_of(page, "room-camera")
    camera = page.locator('room-camera[data-webgl="ok"][data-camera="room"]')
    camera.wait_for()
    wait_for(lambda: bool(camera.get_attribute("data-drawn-pose")), 15, "the robot was never drawn")
    x, y, _ = (float(v) for v in (camera.get_attribute("data-drawn-pose") or "").split())
    assert abs(x) < 4.0 and abs(y) < 3.0, "the robot is drawn inside the room (wherever earlier tests left it)"
    rest = aim(page)
    assert 30 < rest[0] < 45 and 20 < rest[1] < 35 and rest[2] == 60.0, rest  # aimed from a corner at the centre
    camera.get_by_role("button", name="Pan left").click()
    wait_for(lambda: aim(page)[0] == pytest.approx(rest[0] + 10, abs=0.2), 5, "pan did not turn the view")
    camera.locator("canvas").focus()
    page.keyboard.press("ArrowDown")
    page.keyboard.press("+")
    wait_for(lambda: aim(page)[1:] == (pytest.approx(rest[1] + 5, abs=0.2), pytest.approx(48.0, abs=0.1)), 5,
             "the keys did not tilt and zoom")
    for _ in range(12):
        camera.get_by_role("button", name="Pan right").click()
    wait_for(lambda: aim(page)[0] == pytest.approx(rest[0] - 75, abs=0.2), 5, "pan went past the mount's limit")
    assert "Room camera: pan" in (camera.locator('[data-field="room-camera-status"]').text_content() or "")
    camera.get_by_role("button", name="Back to the camera's rest position").click()
    wait_for(lambda: aim(page) == rest, 5, "reset did not bring the camera back")
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    camera.scroll_into_view_if_needed()
    page.screenshot(path=str(ARTIFACTS_DIR / "room-camera-desktop.png"))

    page.set_viewport_size({"width": 390, "height": 844})
    page.reload()
    page.locator('[data-connection="drive"][data-phase="open"]').wait_for()
    show_tab_of(page, "room-camera")
    camera.wait_for()
    wait_for(lambda: bool(camera.get_attribute("data-drawn-pose")), 15, "the phone never drew the robot")
    assert not camera.get_by_role("button", name="Pan left").is_visible(), "a fixed view on a phone"
    camera.scroll_into_view_if_needed()
    page.screenshot(path=str(ARTIFACTS_DIR / "room-camera-phone.png"))
