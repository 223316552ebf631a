"""The camera panel's picture drawn by the browser (three.js, from the robot's scene and where it stands) in
Debian's Chromium against the real three tiers: the person switches to it, the video socket closes (the robot
renders nothing for this viewer), the picture follows the robot, the motion preview and an added delay work on it
as on the video, it does not move with odometry's drift, a graded run turns it to the video, and the person
switches back. While drawn, the panel's words call it a picture, not video; on a
phone it draws at most 15 frames a second, and where WebGL is missing the page says so and shows the video."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from playwright.sync_api import TimeoutError as PlaywrightTimeoutError

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_console import canvas_pixels, log_in, number, wait_for
from tests.e2e.test_feedback import INJECTED_DELAY_S, canvas_data, set_delay
from tests.e2e.test_lab_view import three_installed  # noqa: F401 - the fixture: fail clearly without three.js
from tests.e2e.test_panels import open_console, show_tab_of, wait_for_control

pytestmark = pytest.mark.e2e


def camera_viewers(live_server: LiveServer) -> int:
    """How many of this web process's sockets take lab-1's JPEG stream."""
    from middleware.robots.registry import robot_registry

    return robot_registry(live_server.app).get("lab-1").camera.viewer_count


PHONE = {"viewport": {"width": 390, "height": 844}, "device_scale_factor": 2, "has_touch": True}
MAX_PHONE_FPS = 15
NO_WEBGL = """(() => {
  const original = HTMLCanvasElement.prototype.getContext;
  HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
    return String(kind).startsWith("webgl") ? null : original.call(this, kind, ...rest);
  };
})();"""

# Feeds a panel telemetry at `hz` for `seconds` (poses turning and moving, as a fast stream would bring them) and
# counts what it drew meanwhile: the camera panel's drawn frames, or the lab view's renders.
FAST_POSES = """async ([selector, hz, seconds]) => {
  const panel = document.querySelector(selector);
  let drawn = 0;
  const onFrame = ({ detail }) => { if (detail.source === "drawn") drawn += 1; };
  panel.addEventListener("camera-frame-shown", onFrame);
  const renders = new MutationObserver((records) => { drawn += records.length; });
  if (selector === "lab-view") renders.observe(panel, { attributes: true, attributeFilter: ["data-drawn-pose"] });
  const start = performance.now();
  let sent = 0;
  await new Promise((resolve) => {
    const timer = setInterval(() => {
      sent += 1;
      const pose = { x_m: 0.01 * (sent % 50), y_m: 0, theta_rad: 0.03 * sent };
      panel.telemetry = { type: "telemetry", capture_unix_s: Date.now() / 1000, odometry: { pose }, camera_pose: pose };
      if (performance.now() - start >= seconds * 1000) {
        clearInterval(timer);
        resolve();
      }
    }, 1000 / hz);
  });
  await new Promise((resolve) => setTimeout(resolve, 200));  // the last frame waiting for its turn
  panel.removeEventListener("camera-frame-shown", onFrame);
  renders.disconnect();
  return { sent, drawn, seconds: (performance.now() - start) / 1000 };
}"""


# Draws three frames with the camera panel's own DrawnView from the robot's scene: the same camera pose with the
# odometry a metre apart, then the camera pose a metre on; [first two equal, third differs].
DRIFTED_FRAMES = """async () => {
  const { DrawnView } = await import("/static/panels/camera-panel/drawn-view.js");
  const scene = await (await fetch("/api/robots/lab-1/scene")).json();
  const { view } = await DrawnView.create(scene, 1);
  const pixels = async (odometry, standing) => {
    const frame = await view.frameFrom({ capture_unix_s: 0, odometry: { pose: odometry }, camera_pose: standing });
    const canvas = new OffscreenCanvas(frame.bitmap.width, frame.bitmap.height);
    const context = canvas.getContext("2d");
    context.drawImage(frame.bitmap, 0, 0);
    return Array.from(context.getImageData(0, 0, canvas.width, canvas.height).data).join();
  };
  const standing = { x_m: 0, y_m: 0, theta_rad: 0 };
  const first = await pixels(standing, standing);
  const drifted = await pixels({ x_m: 1, y_m: 0.5, theta_rad: 0.3 }, standing);
  const moved = await pixels(standing, { x_m: 1, y_m: 0.5, theta_rad: 0.3 });
  view.dispose();
  return [first === drifted, first !== moved];
}"""


def choose_source(page, source: str) -> None:
    options = page.locator("camera-panel details.camera__options")
    if options.get_attribute("open") is None:  # folded on a phone: a person unfolds it first
        options.locator("summary").click()
    page.locator('[data-field="camera-source"]').select_option(source)
    page.locator(f'camera-panel[data-source="{source}"]').wait_for(state="attached")


def camera_words(page) -> str:
    """What the camera panel says about its picture: its placeholder, figures and the canvas's label."""
    panel = page.locator("camera-panel")
    return " ".join([panel.locator(".camera__stats").inner_text(), panel.locator("#camera-canvas").get_attribute(
        "aria-label") or "", panel.locator('[data-field="camera-placeholder"]').text_content() or ""]).lower()


def test_the_picture_drawn_here_follows_the_robot_and_the_video_socket_closes(page, live_server: LiveServer) -> None:
    open_console(page, live_server)
    wait_for_control(page)
    wait_for(lambda: number(page, "frame-sequence") > 0, 15, "no video frame was drawn")
    assert camera_viewers(live_server) == 1

    choose_source(page, "drawn")
    # The camera socket is closed on purpose: its status line says where the picture comes from, calmly.
    camera_line = page.locator('[data-connection="camera"][data-phase="off"]')
    camera_line.wait_for()
    assert " ".join(camera_line.inner_text().split()) == (
        "Camera: video off: picture drawn by this browser from where the robot stands")
    danger = "rgb(177, 38, 27)"  # --danger in app.css: the colour of a socket that failed
    assert camera_line.locator(".connection__text").evaluate("e => getComputedStyle(e).color") != danger
    assert camera_line.locator(".connection__dot").evaluate("e => getComputedStyle(e).backgroundColor") != danger
    assert page.locator('[data-connection="camera"][data-phase="closed"]').count() == 0
    wait_for(lambda: camera_viewers(live_server) == 0, 5, "the page still takes the JPEG stream")
    page.locator('camera-panel[data-frame-source="drawn"]').wait_for(state="attached")
    first = number(page, "frame-sequence")
    wait_for(lambda: number(page, "frame-sequence") >= first + 5, 5, "no drawn frames came")
    assert "drawn by this browser" in (page.locator("#camera-canvas").get_attribute("aria-label") or "")
    words = camera_words(page)
    assert "picture age" in words and "picture delay" in words, words
    assert "video" not in words and "live" not in words, f"the drawn picture is called video or live: {words}"
    assert page.locator('[data-field="video-age"]').count() == 1  # the fields tools read keep their names
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-console-drawn.png"))

    before = canvas_pixels(page)
    heading = number(page, "heading-rad")
    page.evaluate("document.activeElement.blur()")
    page.keyboard.down("ArrowLeft")
    time.sleep(1.0)
    page.keyboard.up("ArrowLeft")
    wait_for(lambda: abs(number(page, "heading-rad") - heading) > 0.2, 5, "the robot did not turn")
    wait_for(lambda: canvas_pixels(page) != before, 5, "the drawn picture did not follow the turn")
    page.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-console-drawn-turned.png"))

    # Drawn where the robot truly stands, whatever its odometry says (issue 34, item 11): a metre of drift in the
    # odometry changes nothing in the picture; a metre in where it stands does.
    same_with_drift, moved_changes = page.evaluate(DRIFTED_FRAMES)
    assert same_with_drift, "the drawn picture moved with the odometry"
    assert moved_changes, "the drawn picture did not move with the robot"

    # The odometry panel says how far its numbers are off where the robot stands, and the ways back.
    note = page.evaluate("""() => {
      const panel = document.querySelector("odometry-panel");
      panel.telemetry = { type: "telemetry", odometry: { pose: { x_m: 1.0, y_m: 0.45, theta_rad: 0 } },
        camera_pose: { x_m: 0.1, y_m: 0.0, theta_rad: 0 } };
      const line = panel.querySelector('[data-field="drift"]');
      return line.hidden ? "" : line.textContent;
    }""")
    assert note.startswith("These numbers are 1.0 m off where the robot stands") and "Localize it" in note \
        and "Return to the dock" in note, note

    # A graded run withholds where the robot stands: the panel turns to the server's camera and says why.
    page.evaluate("""() => { document.querySelector("camera-panel").telemetry = { type: "telemetry",
      capture_unix_s: Date.now() / 1000, odometry: { pose: { x_m: 0, y_m: 0, theta_rad: 0 } },
      camera_pose: null }; }""")
    page.locator('camera-panel[data-source="video"]').wait_for(state="attached")
    message = page.locator('camera-panel [data-field="camera-message"]')
    wait_for(lambda: message.is_visible() and (message.text_content() or "").startswith(
        "During your graded run the picture is the robot's own camera video"), 10,
        f"the camera panel does not say why: {message.evaluate('(e) => [e.hidden, e.textContent]')}")
    page.locator('[data-connection="camera"][data-phase="open"]').wait_for()
    page.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-console-graded-run-video.png"))
    page.locator('camera-panel[data-frame-source="video"]').wait_for(state="attached")
    choose_source(page, "drawn")

    choose_source(page, "video")
    page.locator('[data-connection="camera"][data-phase="open"]').wait_for()
    wait_for(lambda: camera_viewers(live_server) == 1, 5, "the video did not come back")
    page.locator('camera-panel[data-frame-source="video"]').wait_for(state="attached")
    assert "video age" in camera_words(page) and "live camera" in camera_words(page)


def test_the_motion_preview_and_an_added_delay_work_on_the_drawn_picture(
    page, live_server: LiveServer, demo_accounts
) -> None:
    set_delay(live_server.app, "student", INJECTED_DELAY_S)
    log_in(page, live_server, "student", demo_accounts["student"])
    page.goto(f"{live_server.url}/lab/lab-1")
    page.locator('[data-connection="drive"][data-phase="open"]').wait_for()
    choose_source(page, "drawn")
    page.locator('camera-panel[data-frame-source="drawn"]').wait_for(state="attached")
    badge = page.locator('[data-field="injected-delay"]')  # announced on the telemetry socket too
    badge.wait_for(state="visible")
    assert "2.5" in badge.text_content()
    wait_for(lambda: canvas_data(page, "outstandingCommands") == 0, 10, "stale commands outstanding at start")

    page.evaluate("document.activeElement.blur()")
    pressed_at = time.monotonic()
    page.keyboard.down("ArrowLeft")
    # The poses come through the same added delay as video frames: only the preview can show the turn this soon.
    wait_for(lambda: canvas_data(page, "warpShiftPx") > 20, 2, "the drawn picture did not move with the key")
    assert time.monotonic() - pressed_at < INJECTED_DELAY_S
    assert canvas_data(page, "outstandingCommands") > 0
    page.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-console-preview.png"))
    time.sleep(0.6)
    page.keyboard.up("ArrowLeft")
    wait_for(lambda: canvas_data(page, "outstandingCommands") == 0, INJECTED_DELAY_S + 8,
             "the delayed poses never caught up with the commands")
    wait_for(lambda: abs(canvas_data(page, "warpShiftPx")) < 0.5, 3, "the warp did not fall back")
    delay_text = page.locator('[data-field="video-delay"]').text_content()
    assert float(delay_text) >= INJECTED_DELAY_S - 0.2, f"measured delay {delay_text} s"


def test_the_admins_default_picture_shows_first_and_the_persons_choice_is_remembered(
    page, chromium, live_server: LiveServer, demo_accounts
) -> None:
    """The admin makes the drawn view the first picture of the lab's robots on the robots page; a student's console
    opens with it (no video socket at all), the student switches to the video, and a reload keeps the video, as
    does the student's other browser: the choice is kept with the account."""
    admin = chromium.new_context(viewport={"width": 1280, "height": 800}).new_page()
    try:
        log_in(admin, live_server, "admin", demo_accounts["admin"])
        admin.locator('[data-field="username"]').first.wait_for(state="attached")
        admin.goto(f"{live_server.url}/admin/robots")
        row = admin.locator('#kind-pictures tr[data-kind="lab"]')
        row.locator('[data-field="picture"]').select_option("drawn")
        row.get_by_role("button", name="Save the picture for lab").click()
        admin.get_by_text("Robots of the kind lab now show the picture drawn by the browser").wait_for()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        admin.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-admin-default-picture.png"), full_page=True)

        open_console(page, live_server)
        page.locator('camera-panel[data-frame-source="drawn"]').wait_for(state="attached")
        assert page.locator("camera-panel").get_attribute("data-source") == "drawn"
        assert page.locator('[data-connection="camera"]').get_attribute("data-phase") == "off"
        assert camera_viewers(live_server) == 0, "the drawn default opened the video socket"

        choose_source(page, "video")
        page.locator('camera-panel[data-frame-source="video"]').wait_for(state="attached")
        wait_for(lambda: page.evaluate("fetch('/api/me/preferences/camera-picture').then((r) => r.json())")
                 == {"value": {"lab": "video"}}, 5, "the choice was not kept with the account")
        page.reload()
        page.locator('[data-connection="camera"][data-phase="open"]').wait_for()
        page.locator('camera-panel[data-frame-source="video"]').wait_for(state="attached")
        assert page.locator("camera-panel").get_attribute("data-source") == "video"
        page.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-console-remembered-video.png"))
        other_browser = chromium.new_context(**PHONE).new_page()  # the same student's phone
        try:
            open_console(other_browser, live_server)
            other_browser.locator('[data-connection="camera"][data-phase="open"]').wait_for()
            assert other_browser.locator("camera-panel").get_attribute("data-source") == "video"
            other_browser.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-console-remembered-on-a-phone.png"))
        finally:
            other_browser.context.close()
    finally:
        admin.goto(f"{live_server.url}/admin/robots")
        row = admin.locator('#kind-pictures tr[data-kind="lab"]')
        row.locator('[data-field="picture"]').select_option("video")
        row.get_by_role("button", name="Save the picture for lab").click()
        admin.context.close()


@contextmanager
def phone_console(chromium, live_server: LiveServer, password: str, init_script: str = "") -> Iterator[Any]:
    """The demo student's console of lab-1 on a phone-sized screen (a tab; its JavaScript errors fail the test)."""
    context = chromium.new_context(**PHONE)
    if init_script:
        context.add_init_script(init_script)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        log_in(page, live_server, "student", password)
        page.locator('[data-field="username"]').first.wait_for(state="attached")
        page.goto(f"{live_server.url}/lab/lab-1")
        yield page
    finally:
        context.close()
    assert not errors, errors


def test_on_a_phone_the_drawn_picture_and_the_lab_view_draw_at_most_15_frames_a_second(
    chromium, live_server: LiveServer, demo_accounts
) -> None:
    with phone_console(chromium, live_server, demo_accounts["student"]) as page:
        page.locator('[data-connection="drive"][data-phase="open"]').wait_for()
        choose_source(page, "drawn")
        page.locator('camera-panel[data-frame-source="drawn"]').wait_for(state="attached")
        wait_for(lambda: number(page, "fps") > 0, 5, "no drawn frames came")
        # At the camera's own resolution, not the twice finer picture of a large screen.
        assert page.locator("#camera-canvas").evaluate("(canvas) => [canvas.width, canvas.height]") == [320, 240]
        camera = page.locator('section[data-panel-id="camera"]')
        camera.scroll_into_view_if_needed()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-phone-drawn.png"))

        # Poses at 60 Hz (the robot's stream brings 10): the newest is drawn at most 15 times a second.
        fed = page.evaluate(FAST_POSES, ["camera-panel", 60, 2.0])
        assert fed["sent"] / fed["seconds"] > 30, f"the poses were not fed fast: {fed}"
        assert fed["drawn"] <= MAX_PHONE_FPS * fed["seconds"] + 2, f"the drawn picture is not capped: {fed}"
        assert fed["drawn"] >= 4 * fed["seconds"], f"the drawn picture stalled: {fed}"

        show_tab_of(page, "lab-view")
        view = page.locator('lab-view[data-webgl="ok"]')
        view.wait_for()
        wait_for(lambda: bool(view.get_attribute("data-drawn-pose")), 15, "the lab view drew no robot")
        # One device pixel per CSS pixel on a phone, whatever its screen's density.
        sizes = view.locator("canvas").evaluate("(canvas) => [canvas.width, canvas.clientWidth]")
        assert sizes[0] == sizes[1], sizes
        fed = page.evaluate(FAST_POSES, ["lab-view", 60, 2.0])
        assert fed["drawn"] <= MAX_PHONE_FPS * fed["seconds"] + 2, f"the lab view is not capped: {fed}"
        assert fed["drawn"] >= 4 * fed["seconds"], f"the lab view stalled: {fed}"
        view.scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / "lab-view-phone-drawn.png"))
        assert page.evaluate("document.documentElement.scrollWidth") <= 390, "the page scrolls sideways"


# The camera message's state and each ancestor's display, hidden attribute and classes, and the tab in view.
HIDDEN_BY = """() => {
  const message = document.querySelector('camera-panel [data-field="camera-message"]');
  const chain = [];
  for (let node = message; node; node = node.parentElement) {
    chain.push(`${node.tagName}${node.hidden ? '[hidden]' : ''} ${getComputedStyle(node).display} .${node.className}`);
  }
  const tab = document.querySelector('[role="tab"][aria-selected="true"]');
  return { text: message?.textContent, chain, tab: tab?.dataset.tab };
}"""


def test_without_webgl_the_page_says_so_and_the_video_comes_back_on_a_phone(
    chromium, live_server: LiveServer, demo_accounts
) -> None:
    # As a browser with WebGL turned off answers: no context of either kind.
    with phone_console(chromium, live_server, demo_accounts["student"], NO_WEBGL) as page:
        page.locator('camera-panel[data-frame-source="video"]').wait_for(state="attached")
        options = page.locator("camera-panel details.camera__options")
        options.locator("summary").click()
        page.locator('[data-field="camera-source"]').select_option("drawn")
        message = page.locator('camera-panel [data-field="camera-message"]')
        try:
            message.filter(has_text="WebGL is turned off or missing").wait_for()
        except PlaywrightTimeoutError:  # seen twice in loaded suite runs, never alone: say what hid it
            ARTIFACTS_DIR.mkdir(exist_ok=True)
            page.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-no-webgl-message-hidden.png"), full_page=True)
            raise AssertionError(f"the WebGL message was not shown: {page.evaluate(HIDDEN_BY)}") from None
        page.locator('camera-panel[data-source="video"]').wait_for(state="attached")
        page.locator('[data-connection="camera"][data-phase="open"]').wait_for()
        first = number(page, "frame-sequence")
        wait_for(lambda: number(page, "frame-sequence") > first, 10, "the video did not come back")
        assert page.locator("camera-panel").get_attribute("data-frame-source") == "video"
        drawn_option = page.locator('[data-field="camera-source"] option[value="drawn"]')
        assert drawn_option.is_disabled() and "WebGL is missing" in (drawn_option.text_content() or "")
        page.locator('section[data-panel-id="camera"]').scroll_into_view_if_needed()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "robot-eye-phone-no-webgl.png"))
        assert page.evaluate("document.documentElement.scrollWidth") <= 390, "the page scrolls sideways"
