"""The 3D lab view in Debian's Chromium against the real three tiers: three.js installed by the project's set-up,
the lab drawn from the robot's scene description, the robot at its odometry pose, at desktop and phone sizes, and
a sentence instead of a blank box where WebGL is missing."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_panels import odometry, open_console, show_tab_of, wait_for, wait_for_control

pytestmark = pytest.mark.e2e
THREE_MODULE = Path(__file__).resolve().parents[2] / "client_ui/static/vendor/node_modules/three/build/three.module.js"
BODY_TOP_Z_M = 0.18  # the body's top face: clearance 0.06 m + height 0.12 m


@pytest.fixture(autouse=True)
def three_installed() -> None:
    if not THREE_MODULE.exists():
        pytest.fail("three.js is not installed: `make test` (or `make three`) runs npm ci in client_ui/static/vendor.")


def drawn_pose(page) -> tuple[float, float, float]:
    text = page.locator("lab-view").get_attribute("data-drawn-pose") or ""
    x, y, theta = (float(v) for v in text.split())
    return x, y, theta


def open_lab_view(page, live_server: LiveServer) -> None:
    open_console(page, live_server)
    wait_for_control(page)
    show_tab_of(page, "lab-view")
    page.locator('lab-view[data-webgl="ok"]').wait_for()
    wait_for(lambda: bool(page.locator("lab-view").get_attribute("data-drawn-pose")), 15, "no robot was drawn")


def test_the_lab_view_draws_the_robot_where_odometry_says_and_follows_it(page, live_server: LiveServer) -> None:
    open_lab_view(page, live_server)
    view = page.locator("lab-view")
    version = page.evaluate("fetch('/api/robots/lab-1/scene').then((r) => r.json()).then((s) => s.version)")
    assert view.get_attribute("data-scene-version") == version
    x, y, theta = drawn_pose(page)
    assert (x, y) == pytest.approx((odometry(page, "x"), odometry(page, "y")), abs=0.02)
    assert int(view.get_attribute("data-laser-hits")) > 100  # the room's walls, all around the half-plane ahead
    assert "laser hits" in view.locator('[data-field="lab-view-summary"]').inner_text()
    view.scroll_into_view_if_needed()
    page.screenshot(path=str(ARTIFACTS_DIR / "lab-view-orbit-desktop.png"))

    # From above, the pixel over the robot's centre is its body's top, lit as the server's camera lights it.
    view.locator('[data-action="view-above"]').click()
    assert view.get_attribute("data-view") == "above"
    drawn = view.evaluate(f"(panel) => panel.drawnColourAt({x}, {y}, {BODY_TOP_Z_M})")
    body = page.evaluate("fetch('/api/robots/lab-1/scene').then((r) => r.json()).then((s) => s.robot_parts"
                         ".find((p) => p.link === 'base_link' && p.shape === 'cylinder').rgba)")
    up_brightness = 0.953  # ambient 0.6 + diffuse 0.35 * 0.894 + specular 0.05 * 0.8, tests/unit/skill_server
    assert drawn is not None
    assert drawn["rgba"][:3] == pytest.approx([round(c * up_brightness * 255) for c in body[:3]], abs=3)
    page.screenshot(path=str(ARTIFACTS_DIR / "lab-view-above-desktop.png"))

    # A target picked on the 2D map stands in the 3D view too.
    canvas = page.locator('map-panel [data-field="map-canvas"]')
    canvas.scroll_into_view_if_needed()
    px, py = page.evaluate("document.querySelector('map-panel').cssPointOf(1.5, -0.5)")
    canvas.click(position={"x": px, "y": py})
    view.locator('[data-field="lab-view-summary"]').filter(has_text="goal (1.5").wait_for()
    goal = view.evaluate("(panel) => panel.drawnColourAt(1.5, -0.5, 0.52)")  # the pin's head
    assert goal is not None and goal["rgba"][0] > 150 > goal["rgba"][1], f"no red pin at the target: {goal}"

    # The robot turns; the drawn heading follows odometry's.
    show_tab_of(page, "drive")
    page.evaluate("document.activeElement.blur()")  # not the tab just clicked: arrows there move between tabs
    page.keyboard.down("ArrowLeft")
    page.wait_for_timeout(1200)
    page.keyboard.up("ArrowLeft")
    wait_for(lambda: abs(odometry(page, "angular")) < 0.01, 10, "the robot did not stop turning")
    show_tab_of(page, "lab-view")
    heading = odometry(page, "heading-rad")
    assert abs(math.remainder(heading - theta, math.tau)) > 0.3, "the robot did not turn"
    wait_for(lambda: abs(math.remainder(drawn_pose(page)[2] - heading, math.tau)) < 0.02, 10,
             "the drawn heading does not follow odometry")


def test_the_lab_view_fits_a_phone(chromium, live_server: LiveServer) -> None:
    context = chromium.new_context(viewport={"width": 390, "height": 844}, device_scale_factor=2, has_touch=True)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        open_lab_view(page, live_server)
        canvas = page.locator('lab-view [data-field="lab-view-canvas"]')
        box = canvas.bounding_box()
        assert box is not None and box["width"] <= 390 and box["width"] > 300
        assert page.evaluate("document.documentElement.scrollWidth") <= 390, "the page scrolls sideways"
        assert page.locator("lab-view").evaluate("(panel) => panel.drawnColourAt(0, 0, 0) !== null")
        canvas.scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / "lab-view-phone.png"))
    finally:
        context.close()
    assert not errors, errors


def test_without_webgl_the_lab_view_says_so(chromium, live_server: LiveServer) -> None:
    context = chromium.new_context(viewport={"width": 1280, "height": 800})
    # As a browser with WebGL turned off answers: no context of either kind.
    context.add_init_script("""(() => {
      const original = HTMLCanvasElement.prototype.getContext;
      HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
        return String(kind).startsWith("webgl") ? null : original.call(this, kind, ...rest);
      };
    })();""")
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        open_console(page, live_server)
        show_tab_of(page, "lab-view")
        view = page.locator('lab-view[data-webgl="missing"]')
        view.wait_for()
        sentence = view.locator('[data-field="lab-view-webgl"]')
        assert "WebGL is turned off or missing" in sentence.inner_text() and sentence.is_visible()
        assert view.locator("canvas").is_hidden()
        page.locator('map-panel [data-field="map-summary"]').filter(has_text="Robot at").wait_for()  # the 2D map
        view.scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / "lab-view-no-webgl.png"))
    finally:
        context.close()
    assert not errors, errors
