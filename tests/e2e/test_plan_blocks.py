"""The plan's blocks in Chromium (Blockly 13 from the vendor lock, under the page's CSP): the demo student opens the
blocks by keyboard, builds a plan by dragging blocks and typing values, reads the text the blocks wrote, checks,
saves and tries it on the practice robot; a text with an on block is drawn as blocks with its error marked on the
block of its line; every demo plan and plan-test plan round-trips through a real Blockly workspace identically; the
blocks fit a phone. Screenshots in test-artifacts/."""

from __future__ import annotations

import time
from collections.abc import Callable

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.unit.plans.test_plan_blocks_roundtrip import TEXTS

pytestmark = pytest.mark.e2e

BUILT = 'say "hello"\ndrive 0.2 0 for 3s\n'
REACTING = """on obstacle_detected 0.4 {
  say "Something ahead"
  drive 0 0.8 for 2s
}
repeat 3 {
  drive 0.2 0 for 1s
}
on wall_lost 2 {
  say "no value here"
}
wait 1s
"""

# In the page: each text loaded into a headless Blockly workspace with the page's own blocks, saved, written back.
ROUND_TRIP = """async (texts) => {
    const form = await import('/static/pages/plans/blocks-form.js');
    const workspace = new window.Blockly.Workspace();
    const failed = [];
    for (const text of texts) {
        window.Blockly.serialization.workspaces.load(form.textToBlocks(text), workspace);
        const back = form.blocksToText(window.Blockly.serialization.workspaces.save(workspace));
        if (back !== text) failed.push([text, back]);
    }
    workspace.dispose();
    return failed;
}"""


def drag_from_toolbox(page, category: str, index: int, to_x: float, to_y: float) -> None:
    """Opens a category of the toolbox and drags its index-th block by its left edge to (to_x, to_y)."""
    page.locator(".blocklyToolboxCategory", has_text=category).click()
    block = page.locator(".blocklyFlyout .blocklyDraggable").nth(index)
    block.wait_for()
    box = block.bounding_box()
    assert box is not None
    grip_x, grip_y = box["x"] + 6, box["y"] + 8
    page.mouse.move(grip_x, grip_y)
    page.mouse.down()
    page.mouse.move(grip_x + 30, grip_y + 10, steps=4)
    page.mouse.move(to_x, to_y, steps=8)
    page.mouse.up()


def text_now(page) -> str:
    return page.get_by_label("The plan's text, one command a line").input_value()


def wait_for_text(page, wanted: Callable[[str], bool]) -> str:
    """The plan's text once wanted holds of it, read as a person reads it (the page's CSP refuses string
    predicates evaluated in the page)."""
    deadline = time.monotonic() + 20
    while not wanted(text := text_now(page)):
        assert time.monotonic() < deadline, text
        page.wait_for_timeout(100)
    return text


def test_a_student_builds_a_plan_with_blocks_and_tries_it(page, app, demo_accounts, live_server: LiveServer) -> None:
    from middleware.lab_runner import seed_demo_course
    from middleware.teaching.practice_robots import practice_manager

    seed_demo_course(app)
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.goto(f"{live_server.url}/login")
    page.get_by_label("Username").fill("student")
    page.get_by_label("Password").fill(demo_accounts["student"])
    page.get_by_role("button", name="Log in").click()
    page.locator('[data-field="username"]').wait_for()
    try:
        page.goto(f"{live_server.url}/plans")
        page.get_by_label("Name").first.fill("blocks-plan")
        page.get_by_role("button", name="Create").click()
        page.wait_for_url("**/plans/*")
        editor = page.get_by_label("The plan's text, one command a line")
        editor.wait_for()
        editor.fill("")
        # By keyboard: the button is reached and pressed like any other.
        toggle = page.get_by_role("button", name="Edit as blocks")
        toggle.focus()
        page.keyboard.press("Enter")
        page.locator("[data-slot=blocks][data-ready=true]").wait_for(timeout=30_000)
        assert page.locator("[data-action=show-blocks]").get_attribute("aria-expanded") == "true"
        page.locator("[data-field=blocks-status]", has_text="0 blocks").wait_for()

        area = page.locator("[data-slot=blocks-area]").bounding_box()
        toolbox = page.locator(".blocklyToolbox").bounding_box()
        assert area is not None and toolbox is not None
        drag_from_toolbox(page, "Say and set", 0, toolbox["x"] + toolbox["width"] + 40, area["y"] + 40)  # say
        wait_for_text(page, lambda text: text.startswith("say"))
        say_box = page.evaluate("""() => {
            const box = window.Blockly.getMainWorkspace().getTopBlocks(false)[0].getSvgRoot().getBoundingClientRect();
            return {x: box.x, y: box.y, height: box.height};
        }""")
        drag_from_toolbox(page, "Move", 0, say_box["x"] + 6, say_box["y"] + say_box["height"] + 8)  # drive, under
        page.locator("[data-field=blocks-status]", has_text="2 blocks").wait_for()
        # The drive was counted when the drag made it; its place under the say comes with the drop's own event.
        wait_for_text(page, lambda text: text == 'say "hello"\ndrive 0.2 0 for 2s\n')
        # A value typed into the drive's time field.
        field = page.evaluate("""() => {
            const drive = window.Blockly.getMainWorkspace().getAllBlocks(false).find((b) => b.type === 'plan_drive');
            const box = drive.getField('TIME').getSvgRoot().getBoundingClientRect();
            return {x: box.x + box.width / 2, y: box.y + box.height / 2};
        }""")
        page.mouse.click(field["x"], field["y"])
        page.locator(".blocklyHtmlInput").fill("3s")
        page.keyboard.press("Enter")
        wait_for_text(page, lambda text: text == BUILT)
        page.screenshot(path=str(ARTIFACTS_DIR / "plan-blocks-built.png"), full_page=True)

        # By keyboard (Blockly's own navigation): Tab reaches the plan's blocks (the one last edited), the arrows go
        # from block to block, each read out by its words.
        page.locator("[data-action=show-blocks]").focus()
        reached = []
        for _ in range(8):
            page.keyboard.press("Tab")
            reached.append(page.evaluate("document.activeElement.getAttribute('aria-label') || ''"))
            if reached[-1].startswith("drive, 0.2, m/s, turn, 0, rad/s, for, 3s"):
                break
        assert reached[-1].startswith("drive, 0.2, m/s, turn, 0, rad/s, for, 3s"), reached
        page.keyboard.press("ArrowUp")
        assert page.evaluate("window.Blockly.getFocusManager().getFocusedNode().type") == "plan_say"
        assert "say, hello" in page.evaluate("document.activeElement.getAttribute('aria-label')")

        page.get_by_role("button", name="Check", exact=True).click()
        page.locator("[data-field=check-status][data-valid=true]").wait_for()
        page.get_by_role("button", name="Save", exact=True).click()
        page.locator("[data-field=check-status]", has_text="Saved as version").wait_for()
        page.get_by_role("radio", name="at the dock").check()
        page.get_by_role("button", name="Try on my practice robot").click()
        page.locator("[data-field=end-state][data-status]").wait_for(timeout=120_000)
        end_state = page.locator("[data-field=end-state]")
        assert end_state.get_attribute("data-status") == "succeeded", end_state.text_content()
        page.screenshot(path=str(ARTIFACTS_DIR / "plan-blocks-tried.png"), full_page=True)

        # A text with on blocks is drawn as blocks; the checker's error is marked on the block of its line.
        editor.fill(REACTING)
        page.locator("[data-field=blocks-status]", has_text="8 blocks").wait_for()
        page.get_by_role("button", name="Check", exact=True).click()
        page.locator("[data-slot=errors] li[data-line='8']").wait_for()
        warned = page.evaluate("""() => window.Blockly.getMainWorkspace().getAllBlocks(false)
            .filter((block) => block.hasIcon(window.Blockly.icons.IconType.WARNING)).map((block) => block.type)""")
        assert warned == ["plan_on"], warned
        assert text_now(page) == REACTING
        page.locator("[data-slot=blocks-area]").scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / "plan-blocks-on-event.png"))

        # Every plan of the demo data and of the plan tests, through a real Blockly workspace: the same text back.
        failed = page.evaluate(ROUND_TRIP, TEXTS)
        assert not failed, failed[:3]

        # On a phone: the blocks fit the screen's width.
        page.set_viewport_size({"width": 390, "height": 844})
        page.goto(page.url.split("?")[0] + "?blocks=1")
        page.locator("[data-slot=blocks][data-ready=true]").wait_for(timeout=30_000)
        assert page.evaluate("document.documentElement.scrollWidth") <= 390, "the blocks scroll sideways on a phone"
        box = page.locator("[data-slot=blocks-area]").bounding_box()
        assert box is not None and box["x"] >= 0 and box["x"] + box["width"] <= 390
        page.locator("[data-slot=blocks-area]").scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / "plan-blocks-phone.png"))
    finally:
        practice_manager(app).shutdown()
