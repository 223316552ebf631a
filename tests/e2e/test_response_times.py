"""The console's response-times panel times the student's own skill activations and drive commands over the 2003
paper's two legs, in Debian's Chromium against the real three tiers; its figures are those of the commands it
timed, and its robot leg is the one the middleware answered each activation with."""

from __future__ import annotations

import math
import re

import pytest

from benchmarks.response_times import (
    FIGURES,
    LEGS,
    activate_and_drive,
    disagreements,
    panel_samples,
    shown_table,
    table_one,
)
from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_panels import open_console, show_tab_of, wait_for, wait_for_control

pytestmark = pytest.mark.e2e
ACTIVATIONS = 3


def test_a_student_reads_the_response_times_of_their_own_activations_and_drive_commands(
    page, live_server: LiveServer
) -> None:
    open_console(page, live_server)
    wait_for_control(page)
    robot_legs = activate_and_drive(page, ACTIVATIONS, drive_s=1.0)
    assert len(robot_legs) == ACTIVATIONS and all(leg > 0 for leg in robot_legs), robot_legs

    show_tab_of(page, "response-times")
    panel = page.locator("response-times-panel")
    panel.locator('[data-field="rtt-skill-count"]').filter(has_text=str(ACTIVATIONS)).wait_for()
    wait_for(lambda: int(panel.locator('[data-field="rtt-drive-count"]').text_content()) >= 5, 5,
             "the drive commands were not timed")
    page.wait_for_timeout(600)  # one more refresh, so the cells show every sample read below
    samples = panel_samples(page)
    shown = shown_table(page)
    # What a person reads is the figures of the commands the panel timed, to its one decimal...
    assert disagreements(shown, table_one(samples)) == []
    # ... and its robot leg is the middleware's own measure, as it answered each activation.
    assert shown["skill"]["robot"]["min"] == pytest.approx(min(robot_legs), abs=0.05)
    assert shown["skill"]["robot"]["max"] == pytest.approx(max(robot_legs), abs=0.05)
    for kind in ("skill", "drive"):
        for leg in LEGS:
            figures = shown[kind][leg]
            assert all(not math.isnan(figures[name]) for name in FIGURES), (kind, leg, figures)
            assert figures["min"] <= figures["mean"] <= figures["max"] and figures["jitter"] >= 0
    assert shown["skill"]["robot"]["max"] < shown["skill"]["total"]["max"]
    sent = int(panel.locator('[data-field="rtt-sent"]').text_content())
    assert sent >= ACTIVATIONS + 5
    assert panel.locator('[data-field="rtt-lost"]').text_content() == "0"
    assert re.fullmatch(r"\d+ B/s|\d+\.\d kB/s", panel.locator('[data-field="rtt-throughput"]').text_content())

    # The odometry panel says when the robot last applied a command, not the wire's 13-digit sequence number.
    applied = page.locator('odometry-panel [data-field="last-applied"]').text_content()
    assert re.fullmatch(r"just now|\d+ s ago", applied), applied

    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.locator('section[data-panel-id="response-times"]').screenshot(path=str(ARTIFACTS_DIR / "response-times.png"))
    page.set_viewport_size({"width": 390, "height": 844})
    page.locator('section[data-panel-id="response-times"]').scroll_into_view_if_needed()
    assert page.evaluate("document.documentElement.scrollWidth") <= 390, "the page scrolls sideways on a phone"
    page.locator('section[data-panel-id="response-times"]').screenshot(
        path=str(ARTIFACTS_DIR / "response-times-phone.png"))
