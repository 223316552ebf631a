"""The camera's feedback layer in Debian's Chromium against the real three tiers, under an injected delay."""

from __future__ import annotations

import math
import time

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_console import log_in, number, wait_for

pytestmark = pytest.mark.e2e

INJECTED_DELAY_S = 2.5


def set_delay(app, username: str, delay_s: float) -> None:
    """Stores the user's injected delay the way the tutor's API does."""
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.experiment.services import set_video_delay
    from middleware.models import User

    with session_factory(app)() as session:
        user = session.scalar(select(User).where(User.username == username))
        admin = session.scalar(select(User).where(User.username == "admin"))
        set_video_delay(session, admin, user.id, delay_s)
        session.commit()


def left_edge_brightness(page) -> float:
    """Mean brightness of the canvas's leftmost 4 columns (black where the warp knows no pixels)."""
    return page.evaluate("""() => {
        const c = document.querySelector('#camera-canvas');
        const d = c.getContext('2d').getImageData(0, 0, 4, c.height).data;
        let sum = 0;
        for (let i = 0; i < d.length; i += 4) sum += d[i] + d[i + 1] + d[i + 2];
        return sum / (d.length / 4) / 3;
    }""")


def live_server_preference(page, key: str):
    """The logged-in user's saved preference, read through the page's session."""
    return page.evaluate(f"fetch('/api/me/preferences/{key}').then((r) => r.json()).then((a) => a.value)")


def canvas_row(page) -> list[int]:
    """Grey levels of the canvas's middle row."""
    return page.evaluate("""() => {
        const c = document.querySelector('#camera-canvas');
        const d = c.getContext('2d').getImageData(0, c.height >> 1, c.width, 1).data;
        return Array.from({length: c.width}, (_, x) => (d[4 * x] + d[4 * x + 1] + d[4 * x + 2]) / 3);
    }""")


def canvas_row_and_shift(page) -> tuple[list[int], float]:
    """The middle row and the shift it was drawn with, read in one task so no redraw comes between them."""
    row, shift = page.evaluate("""() => {
        const c = document.querySelector('#camera-canvas');
        const d = c.getContext('2d').getImageData(0, c.height >> 1, c.width, 1).data;
        return [Array.from({length: c.width}, (_, x) => (d[4 * x] + d[4 * x + 1] + d[4 * x + 2]) / 3),
                Number(c.dataset.warpShiftPx)];
    }""")
    return row, shift


def moved_row(row: list[int], shift: float, x: int) -> float:
    """row at x - shift, linearly interpolated: what a canvas drawn `shift` px to the right shows at x."""
    at = x - shift
    left = math.floor(at)
    weight = at - left
    return row[left] * (1 - weight) + row[left + 1] * weight


def row_error(a: list[int], b: list[int]) -> float:
    return sum(abs(x - y) for x, y in zip(a, b, strict=True)) / max(1, len(a))


def canvas_data(page, name: str) -> float:
    value = page.evaluate(f"document.querySelector('#camera-canvas').dataset.{name}")
    return float(value) if value not in (None, "") else float("nan")


def test_a_key_press_shifts_the_picture_before_the_delayed_video_shows_the_turn(
    page, live_server: LiveServer, demo_accounts
) -> None:
    set_delay(live_server.app, "student", INJECTED_DELAY_S)
    log_in(page, live_server, "student", demo_accounts["student"])
    page.goto(f"{live_server.url}/lab/lab-1")
    page.locator('#console[data-robot="lab-1"]').wait_for()
    page.locator('[data-connection="drive"][data-phase="open"]').wait_for()
    wait_for(lambda: number(page, "frame-sequence") > 0, 15, "no camera frame was drawn")
    badge = page.locator('[data-field="injected-delay"]')
    badge.wait_for(state="visible")
    assert "2.5" in badge.text_content()
    assert page.locator('#camera-canvas').is_visible()
    wait_for(lambda: canvas_data(page, "outstandingCommands") == 0, 10, "stale commands outstanding at start")
    assert left_edge_brightness(page) > 20, "the idle picture should not be black at its edge"
    assert abs(canvas_data(page, "warpShiftPx")) < 0.5
    idle_row = canvas_row(page)

    page.locator("body").focus()
    pressed_at = time.monotonic()
    page.keyboard.down("ArrowLeft")
    wait_for(lambda: canvas_data(page, "warpShiftPx") > 20, 2, "the picture did not move with the key")
    shifted_after_s = time.monotonic() - pressed_at
    # The video cannot show the turn yet: its frames are held 2.5 s; the layer still warps by our commands.
    shifted_row, shift = canvas_row_and_shift(page)
    assert canvas_data(page, "outstandingCommands") > 0
    assert shifted_after_s < INJECTED_DELAY_S
    # The idle picture, moved right by the shift (edge columns and the dashed outline left out).
    span = range(math.ceil(shift) + 5, len(idle_row) - 5)
    moved = row_error([shifted_row[x] for x in span], [moved_row(idle_row, shift, x) for x in span])
    assert moved < 6, f"the shown picture is not the idle one moved {shift} px (error {moved:.1f})"
    # By default the uncovered left part continues the picture's edge instead of black.
    assert left_edge_brightness(page) > 20, "the uncovered part should continue the picture's edge"
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "feedback-turning-under-delay.png"))
    time.sleep(0.6)
    page.keyboard.up("ArrowLeft")
    wait_for(lambda: canvas_data(page, "outstandingCommands") == 0, INJECTED_DELAY_S + 8,
             "the delayed video never caught up with the commands")

    # The thesis's black fill, chosen in the panel, is kept for the next visit.
    page.locator('[data-field="feedback-fill"]').select_option("black")
    wait_for(lambda: live_server_preference(page, "camera-feedback-fill") == "black", 3, "fill choice not saved")
    page.locator("body").focus()
    page.keyboard.down("ArrowLeft")
    wait_for(lambda: canvas_data(page, "warpShiftPx") > 20, 2, "the picture did not move with the key")
    assert left_edge_brightness(page) < 5, "with the black fill, turning left uncovers black at the left edge"
    page.screenshot(path=str(ARTIFACTS_DIR / "feedback-turning-black-fill.png"))
    time.sleep(0.3)
    page.keyboard.up("ArrowLeft")

    # Once the delayed frames show the turn, nothing is outstanding and the picture is unwarped again.
    wait_for(lambda: canvas_data(page, "outstandingCommands") == 0, INJECTED_DELAY_S + 8,
             "the delayed video never caught up with the commands")
    wait_for(lambda: abs(canvas_data(page, "warpShiftPx")) < 0.5, 3, "the warp did not fall back")
    delay_text = page.locator('[data-field="video-delay"]').text_content()
    assert float(delay_text) >= INJECTED_DELAY_S - 0.2, f"measured video delay {delay_text} s"

    # Turned off, the layer leaves the picture alone.
    page.locator('[data-field="feedback-toggle"]').uncheck()
    page.locator("body").focus()
    page.keyboard.down("ArrowRight")
    time.sleep(0.5)
    assert abs(canvas_data(page, "warpShiftPx")) < 0.5
    page.keyboard.up("ArrowRight")
    page.set_viewport_size({"width": 390, "height": 844})
    page.screenshot(path=str(ARTIFACTS_DIR / "feedback-phone.png"), full_page=False)
