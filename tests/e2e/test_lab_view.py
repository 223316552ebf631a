"""The 3D lab view in Debian's Chromium against the real three tiers: three.js installed by the project's set-up,
the lab drawn from the robot's scene description, the robot at its odometry pose, the occupancy map on the floor and
the path planned to a goal, at desktop and phone sizes, and a sentence instead of a blank box where WebGL is
missing."""

from __future__ import annotations

import base64
import math
from pathlib import Path

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_panels import odometry, open_console, show_tab_of, wait_for, wait_for_control, wait_for_status

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


def set_speed_ceiling(page, max_linear_mps: float) -> None:
    """The robot's linear velocity ceiling, as the low-level panel sets it (the student has control)."""
    status = page.evaluate("""(value) => fetch('/api/robots/lab-1/limits', {
      method: 'POST',
      headers: {'Content-Type': 'application/json',
                'X-CSRFToken': document.querySelector('meta[name="csrf-token"]').content},
      body: JSON.stringify({max_linear_mps: value}),
    }).then((answer) => answer.status)""", max_linear_mps)
    assert status == 200, f"the speed ceiling was not set: {status}"


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
    # Slowly (a student may lower the speed ceiling), so that on a loaded host the robot is still well short of
    # the goal when the test reads the path, and the goal is still running when it is cancelled.
    set_speed_ceiling(page, 0.08)
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


UNKNOWN_CELL = 255


def grid_cells(grid: dict) -> list[tuple[float, float, int]]:
    """(x_m, y_m, value) of every cell's centre of an occupancy grid as GET /api/robots/<r>/map answers it."""
    cells = base64.b64decode(grid["cells_b64"])
    width, resolution = grid["width_cells"], grid["resolution_m"]
    return [(grid["origin_x_m"] + (index % width + 0.5) * resolution,
             grid["origin_y_m"] + (index // width + 0.5) * resolution, value) for index, value in enumerate(cells)]


def open_floor_point(grid: dict, x_m: float, y_m: float) -> tuple[float, float]:
    """A cell seen free 0.8-1.5 m from (x_m, y_m) with seen-free cells 0.35 m all round it: somewhere to drive to."""
    cells = grid_cells(grid)
    free = {(round(cx, 3), round(cy, 3)) for cx, cy, value in cells if value < 50}
    step = grid["resolution_m"]
    reach = int(0.35 / step)
    around = [(i * step, j * step) for i in range(-reach, reach + 1) for j in range(-reach, reach + 1)
              if math.hypot(i, j) * step <= 0.35]
    for cx, cy, value in cells:
        if value < 50 and 0.8 <= math.hypot(cx - x_m, cy - y_m) <= 1.5 and all(
                (round(cx + dx, 3), round(cy + dy, 3)) in free for dx, dy in around):
            return cx, cy
    near = [math.hypot(cx - x_m, cy - y_m) for cx, cy, value in cells if value < 50]
    raise AssertionError(f"the map shows no open floor 0.8-1.5 m from the robot at ({x_m:.2f}, {y_m:.2f}): "
                         f"{len(near)} free cells, {sum(0.8 <= d <= 1.5 for d in near)} of them 0.8-1.5 m away")


def test_the_lab_view_draws_the_map_on_the_floor_and_the_path_planned_to_a_goal(page, live_server: LiveServer) -> None:
    open_lab_view(page, live_server)
    view = page.locator("lab-view")
    modelling = page.locator('skill-panel[data-skill="environment_modelling"]')
    modelling.locator('button[data-action="activate"]').click()
    wait_for_status(page, "environment_modelling", "executing")
    # The grid the map panel polls (while a panel that shows it is seen) reaches the 3D view too, as a texture on
    # the floor.
    view.scroll_into_view_if_needed()
    page.locator("lab-view[data-map-cells]").wait_for(state="attached", timeout=20_000)
    view.locator('[data-field="lab-view-summary"]').filter(has_text="on the floor").wait_for()
    # An empty map is drawn on the floor too: wait, as a person would, for the map to hold some scans.
    fetch_map = "fetch('/api/robots/lab-1/map').then((r) => r.json()).then((answer) => answer.map)"
    wait_for(lambda: (page.evaluate(fetch_map) or {}).get("scans_integrated", 0) >= 1, 20, "the map holds no scans")
    grid = page.evaluate(fetch_map)
    assert view.get_attribute("data-map-cells") == f"{grid['width_cells']} {grid['height_cells']}"
    x, y, _ = drawn_pose(page)
    free = open_floor_point(grid, x, y)
    floor = page.evaluate("fetch('/api/robots/lab-1/scene').then((r) => r.json()).then((s) => s.floor)")
    unknown = next((cx, cy) for cx, cy, value in grid_cells(grid)
                   if value == UNKNOWN_CELL and math.hypot(cx - x, cy - y) > 0.5
                   and abs(cx - floor["center_x_m"]) < floor["half_x_m"] - 0.1
                   and abs(cy - floor["center_y_m"]) < floor["half_y_m"] - 0.1)
    view.locator('[data-action="view-above"]').click()
    # The same pixels drawn with the grid and without it, in one task (the wiring's polls cannot come between).
    with_map, without_map = view.evaluate("""(panel, [grid, points]) => {
      panel.map = grid;
      const drawn = () => points.map(([x, y]) => panel.drawnColourAt(x, y, 0).rgba);
      const withMap = drawn();
      panel.map = null;
      const withoutMap = drawn();
      panel.map = grid;
      return [withMap, withoutMap];
    }""", [grid, [list(free), list(unknown)]])
    assert with_map[0] != without_map[0], "a free cell of the map is not drawn on the floor"
    assert sum(with_map[0][:3]) > sum(without_map[0][:3]), "free cells are drawn lighter than the floor"
    assert with_map[1] == without_map[1], "an unknown cell of the map hides the floor"
    view.scroll_into_view_if_needed()
    page.screenshot(path=str(ARTIFACTS_DIR / "lab-view-map-on-floor.png"))

    # Go-to-goal to open floor: the path still ahead, from the feedback, is drawn as a red ribbon on the floor, and
    # the 2D map draws it too.
    # Slowly (a student may lower the speed ceiling), so that on a loaded host the robot is still well short of
    # the goal when the test reads the path, and the goal is still running when it is cancelled.
    set_speed_ceiling(page, 0.08)
    canvas = page.locator('map-panel [data-field="map-canvas"]')
    canvas.scroll_into_view_if_needed()
    px, py = page.evaluate("(point) => document.querySelector('map-panel').cssPointOf(...point)", list(free))
    canvas.click(position={"x": px, "y": py})
    page.locator('map-panel button[data-action="go-there"]').click()
    wait_for_status(page, "go_to_goal", "executing")
    page.locator('lab-view:not([data-path-points="0"])[data-path-points]').wait_for(state="attached", timeout=10_000)
    # Read at one moment: the ribbon is the path still ahead, and the robot drives on while the test looks.
    on_path = view.evaluate("""(panel) => {
      panel.render();
      const points = panel.plannedPath;
      const words = () => ({
        summary: panel.querySelector('[data-field="lab-view-summary"]')?.textContent ?? "",
        legend: Boolean(document.querySelector('map-panel [data-field="map-legend"] [data-layer="path"]')),
      });
      // A point 0.3 m along the path from the robot's pose, past its body.
      let left = 0.3;
      for (let i = 1; i < points.length; i += 1) {
        const [x0, y0] = points[i - 1];
        const [x1, y1] = points[i];
        const length = Math.hypot(x1 - x0, y1 - y0);
        if (length >= left) {
          const x = x0 + ((x1 - x0) * left) / length;
          const y = y0 + ((y1 - y0) * left) / length;
          return { points, colour: panel.drawnColourAt(x, y, 0.02), ...words() };
        }
        left -= length;
      }
      return { points, colour: null, ...words() };
    }""")
    assert "planned path of" in on_path["summary"] and on_path["legend"], on_path
    assert len(on_path["points"]) >= 2
    assert on_path["points"][-1] == pytest.approx(list(free), abs=0.05), "the path does not end at the goal"
    colour = on_path["colour"]
    assert colour is not None and colour["rgba"][0] > 120 > colour["rgba"][1] + 40, f"no red path drawn: {colour}"
    page.screenshot(path=str(ARTIFACTS_DIR / "lab-view-planned-path.png"))

    # An ended goal's path goes; its goal pin may stay.
    page.locator('skill-panel[data-skill="go_to_goal"] button[data-action="cancel"]').click()
    page.locator('lab-view[data-path-points="0"]').wait_for(state="attached", timeout=10_000)
    set_speed_ceiling(page, 0.5)
    page.locator('skill-panel[data-skill="environment_modelling"] button[data-action="cancel"]').click()
    # The session's robot is shared: the next test expects no map.
    page.once("dialog", lambda dialog: dialog.accept())
    page.get_by_role("button", name="Clear the map").click()
    page.locator('map-panel [data-field="map-note"]').filter(has_text="The map was cleared").wait_for()
    view.scroll_into_view_if_needed()
    page.locator("lab-view:not([data-map-cells])").wait_for(state="attached", timeout=10_000)
