"""The console's map as a student and a tutor see it in Chromium against the real three tiers: each pose in its
own labelled style with a trail, the legend listing only what is drawn, the true pose only where allowed, and
"Go there" starting go-to-goal to a point picked on the map."""

from __future__ import annotations

import math
import re

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer
from tests.e2e.test_panels import odometry, open_console, wait_for, wait_for_control, wait_for_status

pytestmark = pytest.mark.e2e


def legend_layers(page) -> set[str]:
    return set(page.locator('map-panel [data-field="map-legend"] li').evaluate_all(
        "(items) => items.map((item) => item.dataset.layer)"))


def create_tutor(live_server: LiveServer, username: str) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory

    with session_factory(live_server.app)() as session:
        create_user(session, username, "tutor", STUDENT_PASSWORD)
        session.commit()


def drive_forward(page, seconds: float) -> None:
    page.evaluate("document.activeElement.blur()")
    page.keyboard.down("ArrowUp")
    page.wait_for_timeout(seconds * 1000)
    page.keyboard.up("ArrowUp")


def test_a_student_sees_odometry_and_its_trail_never_the_truth_and_goes_where_they_click(
        page, live_server: LiveServer) -> None:
    open_console(page, live_server, "student1")
    wait_for_control(page)
    page.get_by_role("tab", name="Navigate").click()
    map_frame = page.locator('section[data-panel-id="map"]')
    map_frame.scroll_into_view_if_needed()
    page.locator('map-panel [data-field="map-note"]').filter(has_text="No map yet").wait_for()
    drive_forward(page, 1.5)
    page.locator('map-panel [data-layer="trail"]').wait_for()
    layers = legend_layers(page)
    # The robot tracks its pose against the floor plan; the skills steer by it, and the map says so.
    assert {"odometry", "tracked", "trail", "laser-tracked", "drift"} <= layers, layers
    undrawn = {"truth", "localized", "particles", "grid"}
    assert not layers & undrawn, f"the legend lists layers that are not drawn: {layers}"
    summary = page.locator('map-panel [data-field="map-summary"]').text_content() or ""
    assert "true pose" not in summary and "tracked against the floor plan" in summary, summary

    # Pick a point 0.6 m behind the robot on the map, then "Go there".
    x0, y0, heading = odometry(page, "x"), odometry(page, "y"), odometry(page, "heading-rad")
    goal = (x0 - 0.6 * math.cos(heading), y0 - 0.6 * math.sin(heading))
    point = page.locator("map-panel").evaluate("(panel, [x, y]) => panel.cssPointOf(x, y)", list(goal))
    go = page.locator('map-panel button[data-action="go-there"]')
    assert go.is_disabled(), "Go there before any target is picked"
    page.locator('map-panel canvas').click(position={"x": point[0], "y": point[1]})
    assert go.is_enabled()
    go.click()
    wait_for_status(page, "go_to_goal", "executing")
    wait_for(lambda: math.hypot(odometry(page, "x") - goal[0], odometry(page, "y") - goal[1]) < 0.45, 30,
             "the robot did not move toward the point picked on the map")
    map_frame.screenshot(path=str(ARTIFACTS_DIR / "map-student-go-there.png"))
    go_to_goal = page.locator('skill-panel[data-skill="go_to_goal"]')
    if go_to_goal.get_attribute("data-status") == "executing":  # near enough: the next test starts from here
        go_to_goal.get_by_role("button", name="Deactivate").click()


def test_a_tutor_sees_the_true_pose_and_the_drift_of_odometry(page, live_server: LiveServer) -> None:
    create_tutor(live_server, "tutor1")
    open_console(page, live_server, "tutor1")
    wait_for_control(page)
    page.get_by_role("tab", name="Navigate").click()
    drive_forward(page, 1.0)
    page.locator('map-panel [data-layer="truth"]').wait_for()
    layers = legend_layers(page)
    assert {"odometry", "truth", "drift", "trail"} <= layers, layers
    assert "localized" not in layers, "no localization runs, so no estimate is drawn or listed"
    page.locator('map-panel [data-field="map-summary"]').filter(
        has_text=re.compile(r"odometry has drifted \d+\.\d\d m from the true pose")).wait_for()
    page.locator('section[data-panel-id="map"]').screenshot(path=str(ARTIFACTS_DIR / "map-tutor-truth-drift.png"))


def test_a_tutor_on_a_phone_docks_a_drifted_robot_without_taking_the_student_s_turn(
        page, chromium, live_server: LiveServer) -> None:
    create_tutor(live_server, "dock-tutor")
    open_console(page, live_server, "student1")
    wait_for_control(page)
    page.get_by_role("tab", name="Navigate").click()
    drive_forward(page, 1.5)
    wait_for(lambda: math.hypot(odometry(page, "x"), odometry(page, "y")) > 0.15, 5, "the robot did not drive")
    student_dock = page.locator('map-panel button[data-action="dock"]')
    assert student_dock.is_enabled(), "the controller may dock the robot"

    phone = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    tutor = phone.new_page()
    try:
        open_console(tutor, live_server, "dock-tutor")
        tutor.locator('queue-panel[data-role="waiting"], queue-panel[data-role="watching"]').wait_for(state="attached")
        tutor.get_by_role("tab", name="Navigate").click()
        dock = tutor.locator('map-panel button[data-action="dock"]')
        dock.scroll_into_view_if_needed()
        assert dock.is_enabled(), "a tutor may dock the robot while observing"
        assert tutor.locator('map-panel button[data-action="go-there"]').is_disabled()
        tutor.once("dialog", lambda dialog: dialog.accept())
        dock.click()
        note = tutor.locator('map-panel [data-field="map-note"]').filter(has_text="back at its dock")
        note.wait_for()
        tutor.locator('section[data-panel-id="map"]').screenshot(path=str(ARTIFACTS_DIR / "map-tutor-docked-390.png"))
    finally:
        phone.close()
    wait_for(lambda: math.hypot(odometry(page, "x"), odometry(page, "y")) < 0.02, 5,
             "the student's odometry did not restart at the dock")
    page.locator('queue-panel[data-role="controller"]').wait_for(state="attached", timeout=1_000)
