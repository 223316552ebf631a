"""Dev aid: drive the pages served by dev_server.py in Debian's Chromium and take screenshots.

NOT the product's e2e tests (those live in tests/e2e and run against the real middleware). This
starts the dev harness on a free port, walks the login page, robot list and console at desktop
(1280x800) and phone (390x844) sizes, writes /tmp/ui-*.png for a person to look at, and checks
the behaviour a screenshot cannot show (driving changes odometry, release stops, reconnects).

Run:  .venv/bin/python client_ui/dev_check.py
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

from playwright.sync_api import Browser, Page, sync_playwright
from werkzeug.serving import make_server

sys.path.insert(0, str(Path(__file__).resolve().parent))
from dev_server import create_app  # noqa: E402

CHROMIUM_ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
    "--disable-sync", "--no-first-run", "--disable-quic",
]
SHOTS = Path("/tmp")
failures: list[str] = []


def check(name: str, ok: bool, detail: object = "") -> None:
    """Record and print one check."""
    print(f"{'ok  ' if ok else 'FAIL'} {name} {detail}")
    if not ok:
        failures.append(name)


def wait_until(predicate: Callable[[], bool], timeout_s: float = 5.0) -> bool:
    """Poll predicate until true or timeout; returns the last result."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.05)
    return predicate()


def number(page: Page, field: str) -> float:
    """The numeric text of [data-field=field], NaN when not a number yet."""
    text = page.locator(f'[data-field="{field}"]').first.text_content() or ""
    try:
        return float(text)
    except ValueError:
        return float("nan")


def watch_errors(page: Page, label: str) -> None:
    """Fail the run on any JavaScript error or console error."""
    page.on("pageerror", lambda error: check(f"{label}: no page error", False, error))
    # A 401 page answer is logged by Chromium as "Failed to load resource"; that is the network, not JS.
    page.on("console", lambda msg: msg.type == "error" and not msg.text.startswith("Failed to load resource")
            and check(f"{label}: no console error", False, msg.text))


def log_in(page: Page, base: str, username: str = "student", password: str = "student") -> None:
    """Log in through the form."""
    page.goto(f"{base}/login")
    page.fill("#username", username)
    page.fill("#password", password)
    page.click("button[type=submit]")


def tab_order(page: Page, presses: int) -> list[str]:
    """Describe the element focused after each Tab press."""
    page.evaluate("document.activeElement && document.activeElement.blur()")
    order = []
    for _ in range(presses):
        page.keyboard.press("Tab")
        order.append(page.evaluate("""() => {
            const e = document.activeElement;
            const name = e.getAttribute('aria-label') || (e.labels && e.labels[0] && e.labels[0].textContent)
                || e.textContent.trim().slice(0, 30);
            return `${e.tagName.toLowerCase()}${e.id ? '#' + e.id : ''} "${name}"`;
        }"""))
    return order


def check_login(browser: Browser, base: str, size: str, viewport: dict[str, int], **context_args: object) -> None:
    """Login page, wrong password, robot list."""
    context = browser.new_context(viewport=viewport, **context_args)
    page = context.new_page()
    watch_errors(page, f"login {size}")
    page.goto(f"{base}/login")
    check(f"login {size}: username has focus",
          wait_until(lambda: page.evaluate("document.activeElement.id") == "username", 2))
    page.screenshot(path=str(SHOTS / f"ui-login-{size}.png"), full_page=True)
    page.fill("#username", "student")
    page.fill("#password", "wrong")
    page.click("button[type=submit]")
    error = page.locator("#login-error")
    check(f"login {size}: error shown", error.is_visible() and "Wrong" in (error.text_content() or ""))
    check(f"login {size}: error role", error.get_attribute("role") == "alert")
    check(f"login {size}: username kept", page.input_value("#username") == "student")
    check(f"login {size}: password focused", page.evaluate("document.activeElement.id") == "password")
    page.screenshot(path=str(SHOTS / f"ui-login-error-{size}.png"), full_page=True)
    page.fill("#password", "student")
    page.click("button[type=submit]")
    page.wait_for_selector(".robot-card")
    check(f"index {size}: two robot cards", page.locator(".robot-card").count() == 2)
    page.screenshot(path=str(SHOTS / f"ui-index-{size}.png"), full_page=True)
    context.close()


def wait_console_live(page: Page) -> None:
    """Until frames, telemetry and the drive link are all up."""
    check("console: frames drawn", wait_until(lambda: number(page, "fps") > 3, 8), number(page, "fps"))
    check("console: telemetry shown", wait_until(lambda: number(page, "x") == number(page, "x"), 5))
    check("console: drive ready", wait_until(lambda: page.locator('[data-field="drive-link"]').is_hidden(), 5))


def check_console_desktop(browser: Browser, base: str) -> None:
    """Console at desktop size: stream, keyboard, pad, focus order, reconnect, session end."""
    context = browser.new_context(viewport={"width": 1280, "height": 800})
    page = context.new_page()
    watch_errors(page, "console desktop")
    log_in(page, base)
    page.goto(f"{base}/lab/lab-1")
    wait_console_live(page)
    check("console: canvas label", page.get_attribute("#camera-canvas", "aria-label") == "Live camera of lab-1")
    box = page.locator("#camera-canvas").bounding_box()
    check("console: canvas is 4:3", box is not None and abs(box["width"] / box["height"] - 4 / 3) < 0.02, box)
    check("console: online badge", page.text_content("#robot-online") == "Online")
    check("console: video age shown", number(page, "video-age") >= 0, number(page, "video-age"))

    order = tab_order(page, 12)
    print("     tab order:", *order, sep="\n       ")
    check("focus: skip link, header, then the pad", order[:4] == [
        'a "Skip to content"', 'a "Telelab"', 'button "Log out"', 'button "Forward"'], order[:4])
    page.focus('[aria-label="Turn left"]')
    page.locator("drive-pad").screenshot(path=str(SHOTS / "ui-console-focus.png"))

    page.evaluate("document.activeElement.blur()")
    x0 = number(page, "x")
    page.keyboard.down("ArrowUp")
    time.sleep(0.3)
    check("drive: Forward lit while ArrowUp held", page.get_attribute('[aria-label="Forward"]', "data-active") == "")
    time.sleep(0.9)
    check("drive: speed shown while driving", number(page, "linear") > 0.2, number(page, "linear"))
    page.keyboard.up("ArrowUp")
    check("drive: ArrowUp moves x", wait_until(lambda: number(page, "x") > x0 + 0.2, 2), (x0, number(page, "x")))
    check("drive: release stops", wait_until(lambda: number(page, "linear") == 0, 1.0), number(page, "linear"))
    check("drive: acks counted", number(page, "ack-sequence") > 10, number(page, "ack-sequence"))
    check("drive: deadman note hidden after a clean stop", page.locator('[data-field="deadman"]').is_hidden())
    page.screenshot(path=str(SHOTS / "ui-console-desktop.png"), full_page=True)

    heading0 = number(page, "heading")
    page.keyboard.down("ArrowLeft")
    time.sleep(0.8)
    page.keyboard.up("ArrowLeft")
    check("drive: ArrowLeft turns left", wait_until(lambda: number(page, "heading") > heading0 + 10, 2),
          (heading0, number(page, "heading")))

    x1 = number(page, "x")
    forward = page.locator('[aria-label="Forward"]').bounding_box()
    assert forward is not None
    page.mouse.move(forward["x"] + forward["width"] / 2, forward["y"] + forward["height"] / 2)
    page.mouse.down()
    time.sleep(0.8)
    page.mouse.up()
    check("pad: mouse hold on Forward moves", wait_until(lambda: abs(number(page, "x") - x1) > 0.1, 2))

    y_before, x_before = number(page, "y"), number(page, "x")
    page.focus('[aria-label="Backward"]')
    page.keyboard.down("Space")
    time.sleep(0.8)
    page.keyboard.up("Space")
    moved = lambda: abs(number(page, "x") - x_before) + abs(number(page, "y") - y_before) > 0.1  # noqa: E731
    check("pad: Space held on Backward moves", wait_until(moved, 2))

    page.evaluate("document.activeElement.blur()")
    page.keyboard.down("ArrowUp")
    time.sleep(0.3)
    page.evaluate("window.dispatchEvent(new Event('blur'))")
    check("drive: window blur stops", wait_until(lambda: number(page, "linear") == 0, 1.0))
    page.keyboard.up("ArrowUp")

    page.request.post(f"{base}/dev/kick")
    check("reconnect: drive shows reconnecting",
          wait_until(lambda: page.get_attribute('[data-connection="drive"]', "data-phase") == "reconnecting", 3))
    page.screenshot(path=str(SHOTS / "ui-console-reconnecting.png"))
    check("reconnect: all back to connected", wait_until(
        lambda: page.locator('[data-connection][data-phase="open"]').count() == 3, 8))
    check("reconnect: drive ready again", wait_until(lambda: page.locator('[data-field="drive-link"]').is_hidden(), 3))
    x2 = number(page, "x")
    page.evaluate("document.activeElement.blur()")
    page.keyboard.down("ArrowUp")
    time.sleep(0.8)
    page.keyboard.up("ArrowUp")
    check("reconnect: driving works on the new socket", wait_until(lambda: number(page, "x") != x2, 2))

    context.clear_cookies()
    page.request.post(f"{base}/dev/kick")
    check("session end: alert shown", wait_until(lambda: page.locator("#session-ended").is_visible(), 8))
    check("session end: camera closed with 4401", wait_until(
        lambda: page.get_attribute('[data-connection="camera"]', "data-code") == "4401", 8))
    check("session end: login link", page.get_attribute("#session-ended a", "href") == "/login")
    check("session end: drive says closed", wait_until(
        lambda: "closed" in (page.text_content('[data-field="drive-link"]') or ""), 8))
    page.screenshot(path=str(SHOTS / "ui-console-session-ended.png"))
    context.close()


def check_other_pages(browser: Browser, base: str) -> None:
    """Offline robot and unknown robot."""
    context = browser.new_context(viewport={"width": 1280, "height": 800})
    page = context.new_page()
    log_in(page, base)
    page.goto(f"{base}/lab/lab-2")
    check("offline: camera says offline", wait_until(
        lambda: "offline" in (page.text_content('[data-field="camera-message"]') or ""), 5))
    check("offline: badge", wait_until(lambda: page.text_content("#robot-online") == "Offline", 3))
    time.sleep(1.5)
    page.screenshot(path=str(SHOTS / "ui-console-offline.png"), full_page=True)
    code = page.evaluate("""() => new Promise((resolve) => {
        const socket = new WebSocket(`ws://${location.host}/ws/robots/nope/camera`);
        socket.onclose = (event) => resolve(event.code);
    })""")
    check("unknown robot: socket closes with 4404", code == 4404, code)
    page.goto(f"{base}/lab/nope")
    check("unknown robot: friendly 404", page.text_content("#error-heading") == "No such robot")
    page.screenshot(path=str(SHOTS / "ui-error.png"), full_page=True)
    context.close()


def check_phone(browser: Browser, base: str) -> None:
    """Console on a phone: layout and press-and-hold by touch."""
    context = browser.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True,
                                  device_scale_factor=1)
    page = context.new_page()
    watch_errors(page, "console phone")
    log_in(page, base)
    page.goto(f"{base}/lab/lab-1")
    wait_console_live(page)
    width = page.evaluate("document.documentElement.scrollWidth")
    check("phone: no horizontal scroll", width <= 390, width)
    page.screenshot(path=str(SHOTS / "ui-console-phone.png"), full_page=True)

    forward = page.locator('[aria-label="Forward"]')
    forward.scroll_into_view_if_needed()
    box = forward.bounding_box()
    assert box is not None
    check("phone: pad buttons are big enough to touch", box["width"] >= 44 and box["height"] >= 44, box)
    x0 = number(page, "x")
    cdp = context.new_cdp_session(page)
    point = {"x": box["x"] + box["width"] / 2, "y": box["y"] + box["height"] / 2}
    cdp.send("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": [point]})
    time.sleep(0.8)
    check("phone: Forward lit while touched", forward.get_attribute("data-active") == "")
    cdp.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
    check("phone: touch hold moves x", wait_until(lambda: abs(number(page, "x") - x0) > 0.1, 2),
          (x0, number(page, "x")))
    check("phone: touch release stops", wait_until(lambda: number(page, "linear") == 0, 1.0))
    page.screenshot(path=str(SHOTS / "ui-console-phone-pad.png"))
    context.close()


def main() -> int:
    """Run every check; exit status 1 when any failed."""
    server = make_server("127.0.0.1", 0, create_app(), threaded=True)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    base = f"http://127.0.0.1:{server.server_port}"
    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path="/usr/bin/chromium", args=CHROMIUM_ARGS)
            check_login(browser, base, "desktop", {"width": 1280, "height": 800})
            check_login(browser, base, "phone", {"width": 390, "height": 844}, is_mobile=True, has_touch=True)
            check_console_desktop(browser, base)
            check_other_pages(browser, base)
            check_phone(browser, base)
            browser.close()
    finally:
        server.shutdown()
    print(f"\n{len(failures)} failed" if failures else "\nall checks passed", *failures, sep="\n  ")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
