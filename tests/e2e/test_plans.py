"""The plans journey in Chromium as the demo student: write a plan with an error, see it marked on its line, fix
it, save it, try it (a prediction in fast mode on a simulated copy of lab-1, from where lab-1 stands now), see the
prediction's progress, then its trace drawn and its end state; run it on lab-1 once the turn is held, its trace
beside the prediction with the distance between their ends; the seeded plans listed; and the same prediction at
phone size. Screenshots in test-artifacts/."""

from __future__ import annotations

import re
import time

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer

pytestmark = pytest.mark.e2e

WITH_ERROR = 'say "Hello"\nfly_to 1 2\ndrive 0.2 0 for 1.5s\n'
FIXED = 'say "Hello"\ndrive 0.2 0 for 4s\nturn_to 90deg\ndrive 0.15 0 for 3s\n'

# Every text the prediction's progress line shows, in order (it changes faster than a test can poll it).
RECORD_PROGRESS = """() => {
    window.progressSeen = [];
    const line = document.querySelector('[data-field=progress]');
    new MutationObserver(() => window.progressSeen.push(line.textContent)).observe(
        line, {childList: true, characterData: true, subtree: true});
}"""


def try_and_see_the_prediction(page, shot: str) -> None:
    """Clicks Try, reads the prediction's progress, then its outcome and trace; a screenshot of the end."""
    page.evaluate(RECORD_PROGRESS)
    page.get_by_role("button", name="Try on my practice robot").click()
    page.locator("[data-field=end-state][data-status]").wait_for(timeout=120_000)
    seen = page.evaluate("window.progressSeen")
    assert any(text.startswith("Prediction: Starting a simulated copy of lab-1") for text in seen), seen
    assert any(text.startswith("Prediction: running line ") for text in seen), seen
    end_state = page.locator("[data-field=end-state]")
    assert end_state.get_attribute("data-status") == "succeeded", end_state.text_content()
    assert end_state.text_content() == "Prediction: SUCCEEDED"
    start = page.locator("[data-field=start]").text_content()
    assert start.startswith("Prediction on a fast simulated copy: Starts where lab-1 stands now"), start
    assert "s of plan predicted in" in start, start
    page.wait_for_function("Number(document.querySelector('[data-field=map]').dataset.predictedPoints) >= 20",
                           timeout=10_000)
    page.locator("[data-field=map]").scroll_into_view_if_needed()
    page.screenshot(path=str(ARTIFACTS_DIR / shot))


def dock_as_its_controller(app, robot_name: str, username: str) -> None:
    """username, who holds the turn on robot_name, sends it to its dock (the console's Return to dock)."""
    from sqlalchemy import select

    from middleware.access.commands import robot_commands
    from middleware.db import session_factory
    from middleware.models import User

    with session_factory(app)() as session:
        user_id = session.scalar(select(User.id).where(User.username == username))
    with app.app_context():
        robot_commands().for_user(robot_name, user_id).return_to_dock()


def test_the_demo_student_fixes_a_plan_and_tries_it_on_the_practice_robot(
        page, app, demo_accounts, live_server: LiveServer) -> None:
    from middleware.lab_runner import seed_demo_course
    from middleware.teaching.practice_robots import practice_manager

    seed_demo_course(app)  # with the demo course, its plans (what `telelab up` seeds)
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.goto(f"{live_server.url}/login")
    page.get_by_label("Username").fill("student")
    page.get_by_label("Password").fill(demo_accounts["student"])
    page.get_by_role("button", name="Log in").click()
    page.locator('[data-field="username"]').wait_for()
    try:
        page.goto(f"{live_server.url}/plans")
        page.locator("[data-slot=mine] a", has_text="square").wait_for()
        page.locator("[data-slot=shared] a", has_text="careful-forward").wait_for()

        page.get_by_label("Name").first.fill("first-plan")
        page.get_by_role("button", name="Create").click()
        page.wait_for_url("**/plans/*")
        editor = page.get_by_label("The plan's text, one command a line")
        editor.fill(WITH_ERROR)
        page.get_by_role("button", name="Check", exact=True).click()
        page.locator(".plan-code__line--error[data-line='2']").wait_for()
        problem = page.locator("[data-slot=errors] li").first
        assert problem.text_content().startswith("Line 2"), problem.text_content()
        assert page.locator(".plan-code__line--error").count() == 1
        page.screenshot(path=str(ARTIFACTS_DIR / "plans-error-marked.png"))

        editor.fill(FIXED)
        editor.press("Control+Enter")  # the keyboard checks as the button does
        page.locator("[data-field=check-status][data-valid=true]").wait_for()
        assert page.locator(".plan-code__line--error").count() == 0
        page.get_by_role("button", name="Save", exact=True).click()
        page.locator("[data-field=check-status]", has_text="Saved as version 2").wait_for()

        assert page.get_by_role("radio", name="where lab-1 stands now").is_checked()
        assert page.get_by_role("radio", name="at the dock").count() == 1
        # With the turn on lab-1, the real run is drawn beside the prediction with the distance between their ends.
        assert page.get_by_role("button", name="Run on lab-1").count() == 0, "offered before the turn is held"
        page.get_by_role("button", name="Queue for the lab robot").click()
        page.get_by_role("button", name="Run on lab-1").wait_for(timeout=30_000)
        dock_as_its_controller(app, "lab-1", "student")  # the suite's lab-1 stands wherever earlier tests left it
        try_and_see_the_prediction(page, "plans-predicted.png")
        page.get_by_role("button", name="Run on lab-1").click(timeout=30_000)
        page.locator("[data-field=end-state]", has_text="lab-1:").wait_for(timeout=60_000)
        page.wait_for_function("Number(document.querySelector('[data-field=map]').dataset.realPoints) >= 1",
                               timeout=10_000)
        apart = page.locator("[data-field=end-error]").text_content()
        match = re.search(r"end points ([0-9.]+) cm apart", apart)
        assert match, apart
        print(f"lab-1's end point and the prediction's: {match.group(1)} cm apart")
        assert float(match.group(1)) <= 10.0, apart  # both started where lab-1 stood; nobody moved it in between
        page.screenshot(path=str(ARTIFACTS_DIR / "plans-run-on-lab.png"), full_page=True)

        page.set_viewport_size({"width": 390, "height": 844})
        page.reload()
        editor.wait_for()
        assert page.evaluate("document.documentElement.scrollWidth") <= 390, "the editor scrolls sideways on a phone"
        box = editor.bounding_box()
        assert box is not None and box["x"] >= 0 and box["x"] + box["width"] <= 390
        page.screenshot(path=str(ARTIFACTS_DIR / "plans-editor-phone.png"), full_page=True)
        # The same prediction on a phone: progress, outcome and trace, the map within the screen's width.
        try_and_see_the_prediction(page, "plans-predicted-phone.png")
        assert page.evaluate("document.documentElement.scrollWidth") <= 390, "the map scrolls sideways on a phone"

        # A long prediction shows the line running while it runs; Cancel stops it, and its robot with it.
        editor.fill('say "spin"\ndrive 0 0.3 for 120s\n')
        page.get_by_role("button", name="Save", exact=True).click()
        page.locator("[data-field=check-status]", has_text="Saved as version 3").wait_for()
        page.get_by_role("button", name="Try on my practice robot").click()
        page.locator("[data-field=progress]", has_text="Prediction: running line 2: drive 0 m/s 0.3 rad/s").wait_for(
            timeout=60_000)
        assert page.locator(".plan-code__line--running[data-line='2']").count() == 1
        page.screenshot(path=str(ARTIFACTS_DIR / "plans-predicting-phone.png"))
        page.get_by_role("button", name="Cancel").click()
        page.locator("[data-field=progress]", has_text="Prediction: cancelled.").wait_for()
        assert not page.get_by_role("button", name="Cancel").is_visible()
        farm = practice_manager(live_server.app).farm
        deadline = time.monotonic() + 15
        while any(r.name.startswith("predict-") for r in farm.robots()) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not any(r.name.startswith("predict-") for r in farm.robots()), "the cancelled prediction's robot runs on"

        # A plan that fails is predicted ABORTED at its line.
        editor.fill('drive 0.1 0 for 1s\nwait_until obstacle_within 0.05 timeout 1s\n')
        page.get_by_role("button", name="Save", exact=True).click()
        page.locator("[data-field=check-status]", has_text="Saved as version 4").wait_for()
        page.get_by_role("button", name="Try on my practice robot").click()
        page.locator("[data-field=end-state][data-status]").wait_for(timeout=120_000)
        aborted = page.locator("[data-field=end-state]").text_content()
        assert aborted.startswith("Prediction: ABORTED at line 2 (TIMEOUT): obstacle_within 0.05 did not hold"), aborted
        page.screenshot(path=str(ARTIFACTS_DIR / "plans-predicted-aborted-phone.png"))

        # Unsaved changes: the prediction says it runs the version as saved.
        editor.fill('wait 0.5s\n')
        page.get_by_role("button", name="Try on my practice robot").click()
        unsaved_note = "It runs version 4, as saved: save to predict your changes."
        page.locator("[data-field=start]", has_text=unsaved_note).wait_for(timeout=60_000)
        page.locator("[data-field=end-state][data-status]").wait_for(timeout=120_000)
    finally:
        practice_manager(live_server.app).shutdown()


def test_a_plan_used_as_a_skill_is_a_console_panel_that_runs_it_with_its_line_progress(
        page, live_server: LiveServer) -> None:
    from tests.e2e.test_panels import open_console, show_tab_of, wait_for_control

    open_console(page, live_server)
    plan = page.evaluate("""async () => {
        const csrf = document.querySelector('meta[name="csrf-token"]').content;
        const headers = {"Content-Type": "application/json", "X-CSRFToken": csrf, Accept: "application/json"};
        const made = await fetch("/api/plans", {method: "POST", headers,
          body: JSON.stringify({name: "two-steps", text: 'say "one"\\ndrive 0.1 0 for 2s\\n'})});
        return (await made.json()).plan;
    }""")
    page.goto(f"{live_server.url}/plans/{plan['id']}")
    page.get_by_label("Use as a skill").check()
    page.locator("[data-field=check-status]", has_text="now a panel in your consoles").wait_for()
    page.goto(f"{live_server.url}/lab/lab-1")
    wait_for_control(page)
    show_tab_of(page, f"plan-{plan['id']}")
    frame = page.locator(f'section[data-panel-id="plan-{plan["id"]}"]')
    frame.get_by_role("heading", name="Plan two-steps").wait_for()
    panel = frame.locator("plan-panel")
    panel.get_by_role("button", name="Run").click()
    panel.locator("[data-field=plan-status]", has_text="Running line 2").wait_for(timeout=15_000)
    page.locator("plan-panel[data-status=succeeded]").wait_for(timeout=30_000)
    assert panel.locator("[data-field=plan-status]").text_content() == "SUCCEEDED"
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "plans-console-skill.png"))


def test_a_tutor_shares_a_plan_and_a_student_reads_it_and_copies_it(page, chromium, live_server: LiveServer) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from tests.conftest import STUDENT_PASSWORD, make_course
    from tests.e2e.test_lessons import log_in

    with session_factory(live_server.app)() as session:
        create_user(session, "tutor7", "tutor", STUDENT_PASSWORD)
        session.commit()
    make_course(live_server.app, "ROB7", {"tutor7": "tutor", "student1": "student"})
    log_in(page, live_server, "tutor7")
    page.goto(f"{live_server.url}/plans")
    page.get_by_label("Name").first.fill("for-my-class")
    page.get_by_role("button", name="Create").click()
    page.wait_for_url("**/plans/*")
    page.get_by_label("Share with a course I teach").select_option(label="ROB7 · Course ROB7")
    page.get_by_role("button", name="Share", exact=True).click()
    page.locator("[data-field=check-status]", has_text="Shared with ROB7").wait_for()

    context = chromium.new_context(viewport={"width": 1280, "height": 800})
    student = context.new_page()
    try:
        log_in(student, live_server, "student1")
        student.goto(f"{live_server.url}/plans")
        student.locator("[data-slot=shared] a", has_text="for-my-class").click()
        student.locator("[data-field=plan-about]", has_text="shared with you to read and run").wait_for()
        assert student.get_by_role("button", name="Save", exact=True).count() == 0
        assert student.get_by_label("The plan's text, one command a line").get_attribute("readonly") is not None
        student.get_by_role("button", name="Copy to my plans").click()
        student.locator("[data-field=plan-about]", has_text="Your plan").wait_for()
        assert student.get_by_role("button", name="Save", exact=True).count() == 1
    finally:
        context.close()


def test_the_plan_pages_pure_helpers_work_in_the_page(page, live_server: LiveServer) -> None:
    from tests.e2e.test_lessons import log_in

    log_in(page, live_server)
    page.goto(f"{live_server.url}/plans")
    results = page.evaluate("""async () => {
        const trace = await import('/static/pages/plans/plan-trace.js');
        const panel = await import('/static/panels/plan-panel/plan-panel.js');
        let points = trace.addSample([], {x_m: 0, y_m: 0});
        points = trace.addSample(points, {x_m: 0.005, y_m: 0});  // under 1 cm: replaces the last point
        points = trace.addSample(points, {x_m: 0.5, y_m: 0});
        points = trace.addSample(points, {x_m: NaN, y_m: 0});
        return {
          points: points.length,
          apart: trace.endErrorCm([{x_m: 0, y_m: 0}], [{x_m: 0.03, y_m: 0.04}]),
          none: trace.endErrorCm([], [{x_m: 0, y_m: 0}]),
          line: trace.lineOf({values: {line: 3}, state: "line 3: drive"}),
          lineFromState: trace.lineOf({values: {}, state: "line 7: wait"}),
          aborted: trace.endStateWords({status: "aborted", error_code: "TIMEOUT",
                                        message: "line 4: the condition did not hold in 10 s"}),
          succeeded: trace.endStateWords({status: "succeeded", message: ""}),
          running: panel.planGoalWords({status: "executing"}, {values: {line: 2}, state: "line 2: drive"}),
        };
    }""")
    assert results == {"points": 2, "apart": 5.0, "none": None, "line": 3, "lineFromState": 7,
                       "aborted": "ABORTED at line 4 (TIMEOUT): the condition did not hold in 10 s",
                       "succeeded": "SUCCEEDED", "running": "Running line 2: drive"}


def test_what_a_student_types_while_the_plan_loads_is_not_overwritten(page, live_server: LiveServer) -> None:
    """On a slow connection the editor takes the stored text only after it arrives; a box a person could type into
    before then would be overwritten by it (the check's error marks too). It stays read-only until then."""
    from tests.e2e.test_lessons import log_in
    from tests.e2e.test_spanish_plans import CREATE

    log_in(page, live_server)
    page.goto(f"{live_server.url}/plans")
    plan_id = page.evaluate(CREATE, "slow-load")

    def slowly(route) -> None:
        time.sleep(1.5)  # Playwright's sync routes run on this thread: the page's fetch waits meanwhile
        route.continue_()

    page.route(re.compile(rf".*/api/plans/{plan_id}$"), slowly)
    page.goto(f"{live_server.url}/plans/{plan_id}", wait_until="commit")
    editor = page.get_by_label("The plan's text, one command a line")
    editor.fill('say "mine"\n')  # waits while the box is read-only, as a person cannot type into it
    page.wait_for_timeout(2000)
    assert editor.input_value() == 'say "mine"\n'
