"""A student's Python exercise in Chromium: Pyodide runs their code in a worker against their practice robot, the
server grades the run from the robot's own record; Stop interrupts an endless loop and stops the robot; an
exception shows its line; a closed tab stops the robot within the deadman's time. Desktop and phone."""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Iterator

import pytest
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from tests.conftest import ARTIFACTS_DIR, LiveServer, make_course, served_lab
from tests.e2e.test_lessons import log_in
from tests.integration.exercises import solutions

pytestmark = pytest.mark.e2e

BUMP_AND_GO = """from telelab import robot

print("bump and go: starting")
turning_until = 0.0
while robot.tick():
    if robot.time() < turning_until:
        robot.set_velocity(0.0, 1.2)
    elif robot.front_distance() < 0.6:
        print("obstacle at", round(robot.time(), 1), "s")
        turning_until = robot.time() + 1.2
    else:
        robot.set_velocity(0.4, 0.0)
"""
ENDLESS = """from telelab import robot
robot.set_velocity(0.3, 0.0)
robot.tick()
print("looping forever")
while True:
    pass
"""
STUBBORN = """from telelab import robot
robot.tick()
print("ignoring Stop")
while True:
    try:
        while True:
            pass
    except KeyboardInterrupt:
        pass
"""
FAILING = """from telelab import robot
robot.tick()

def speed():
    return 1 / 0

robot.set_velocity(speed(), 0.0)
"""


@pytest.fixture(scope="module")
def exercise_lab(tmp_path_factory: pytest.TempPathFactory, skill_server_address: str) -> Iterator[LiveServer]:
    from middleware.teaching.practice_robots import practice_manager

    with served_lab(f"lab-1={skill_server_address}", tmp_path_factory.mktemp("exercises")) as server:
        make_course(server.app, "EX1", {"student1": "student", "tutor1": "tutor"})
        try:
            yield server
        finally:
            practice_manager(server.app).shutdown()


def set_code(page, text: str) -> None:
    """Replaces the editor's text as a person would: select all, then type (paste) the program."""
    page.locator(".cm-content").click()
    page.keyboard.press("Control+a")
    page.keyboard.press("Delete")
    page.keyboard.insert_text(text)
    typed = page.locator(".cm-content").inner_text().replace("\xa0", " ")
    assert [line.rstrip() for line in typed.splitlines() if line.strip()] == \
        [line.rstrip() for line in text.splitlines() if line.strip()], typed


PLACEMENT_SPEED_MPS = 1.5  # faster than any robot's ceiling: a step this fast is a placement


def truth_speed(server: LiveServer, robot_name: str, seconds: float = 0.6) -> float:
    """How far the robot truly drove over the last `seconds`, per second, from its own pose log. A step faster than
    any robot drives is the robot being placed at a run's start, not driving (counted, it let a test see a robot move
    that its program had not moved yet, and Stop it before its run had a trace)."""
    from middleware.robots.registry import robot_registry

    with server.app.app_context():
        link = robot_registry().get(robot_name)
        now = time.time()
        samples = link.pose_log(now - seconds, now).samples
    driven = 0.0
    for before, after in itertools.pairwise(samples):
        step = ((after.ground_truth.x_m - before.ground_truth.x_m) ** 2
                + (after.ground_truth.y_m - before.ground_truth.y_m) ** 2) ** 0.5
        if step <= PLACEMENT_SPEED_MPS * max(after.unix_s - before.unix_s, 0.05):
            driven += step
    return driven / seconds


def wait_until(check, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if check():
            return
        time.sleep(0.1)
    raise AssertionError(what)


def test_a_student_runs_submits_stops_and_reads_errors_in_the_browser(page, exercise_lab: LiveServer) -> None:
    log_in(page, exercise_lab)
    page.goto(f"{exercise_lab.url}/exercises")
    page.get_by_role("link", name="Bump and go").click()
    page.get_by_role("status").filter(has_text="Python").filter(has_text="is ready").wait_for(timeout=90_000)
    assert page.evaluate("window.crossOriginIsolated")
    # The template runs as it is: the student sees it.
    assert "robot.tick()" in page.locator(".cm-content").inner_text()
    set_code(page, BUMP_AND_GO)
    page.get_by_role("button", name="Run on my practice robot").click()
    page.get_by_role("status").filter(has_text="Running on practice-student1").wait_for(timeout=90_000)
    # Run cannot be pressed again while it runs, and looks it (a primary button kept its colour when disabled).
    run_button = page.get_by_role("button", name="Run on my practice robot")
    assert run_button.is_disabled() and run_button.evaluate("button => getComputedStyle(button).opacity") == "0.5"
    console = page.locator("[data-field=console]")
    console.filter(has_text="bump and go: starting").wait_for(timeout=15_000)
    # It moves: the odometry line shows a speed, and the robot truly moves.
    wait_until(lambda: float(page.locator("[data-field=robot]").get_attribute("data-speed") or 0) > 0.2, 15,
               "the robot's odometry never showed it moving")
    wait_until(lambda: truth_speed(exercise_lab, "practice-student1") > 0.2, 10, "the robot did not truly move")
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "exercise-running.png"), full_page=True)
    page.get_by_role("button", name="Stop").click()
    page.locator("[data-field=grade]").filter(has_text="Practice run").wait_for(timeout=20_000)
    wait_until(lambda: truth_speed(exercise_lab, "practice-student1") < 0.02, 5, "the robot kept moving after Stop")

    # Submit: a hidden start, the whole time limit, a grade from the robot's record.
    page.get_by_role("button", name="Submit for a grade").click()
    page.get_by_role("status").filter(has_text="Running on").wait_for(timeout=30_000)
    grade = page.locator("[data-field=grade]").filter(has_text="Submission")
    grade.wait_for(timeout=90_000)
    assert "%" in grade.inner_text()
    assert page.locator("[data-slot=measurements] tbody tr").count() == 3
    page.screenshot(path=str(ARTIFACTS_DIR / "exercise-graded.png"), full_page=True)

    # An endless loop: Stop interrupts it and the robot stops.
    set_code(page, ENDLESS)
    page.get_by_role("button", name="Run on my practice robot").click()
    console.filter(has_text="looping forever").wait_for(timeout=30_000)
    # A loop that no longer ticks: the page stops the robot (its drive session would repeat the last command to the
    # deadman for ever), and says so, before anyone presses Stop.
    console.filter(has_text="No robot.tick() for a while: the robot was stopped.").wait_for(timeout=5_000)
    wait_until(lambda: truth_speed(exercise_lab, "practice-student1") < 0.02, 5, "a loop without ticks kept it going")
    page.get_by_role("button", name="Stop").click()
    console.filter(has_text="Stopped").wait_for(timeout=10_000)
    wait_until(lambda: truth_speed(exercise_lab, "practice-student1") < 0.02, 5, "an endless loop kept the robot going")
    page.get_by_role("button", name="Run on my practice robot").wait_for()

    # A program that swallows the interrupt: Python is replaced, and the next run waits until it has loaded again
    # (it once started on the loading worker and never ended).
    set_code(page, STUBBORN)
    page.get_by_role("button", name="Run on my practice robot").click()
    console.filter(has_text="ignoring Stop").wait_for(timeout=30_000)
    page.get_by_role("button", name="Stop").click()
    console.filter(has_text="Python is restarted").wait_for(timeout=10_000)
    console.filter(has_text="Python has loaded again").wait_for(timeout=60_000)

    # An exception: the student's line and the traceback.
    set_code(page, FAILING)
    page.get_by_role("button", name="Run on my practice robot").click()
    console.filter(has_text="Line 5: ZeroDivisionError").wait_for(timeout=30_000)
    assert "exercise.py" in console.inner_text()
    assert page.locator(".exercise__error-line").count() == 1
    page.get_by_role("status").filter(has_text="What the robot did until then is graded below").wait_for(timeout=20_000)
    page.screenshot(path=str(ARTIFACTS_DIR / "exercise-error.png"), full_page=True)


def test_a_tutor_reads_each_students_code_versions_runs_and_grades(chromium, exercise_lab: LiveServer) -> None:
    context = chromium.new_context(viewport={"width": 1280, "height": 800})
    page = context.new_page()
    try:
        log_in(page, exercise_lab, "tutor1")
        page.goto(f"{exercise_lab.url}/exercises")
        page.get_by_role("link", name="Students' code, runs and grades").first.click()
        student = page.locator('[data-student="student1"]')
        student.wait_for()
        assert "best submission" in student.inner_text()
        student.locator("summary").first.click()
        assert "robot.tick()" in student.locator("pre").first.inner_text()
        page.screenshot(path=str(ARTIFACTS_DIR / "exercise-class.png"), full_page=True)
    finally:
        context.close()


def test_a_tutor_makes_an_exercise_a_courses_test_on_its_page_and_the_student_reads_it(
        chromium, exercise_lab: LiveServer) -> None:
    for size, viewport in (("desktop", {"width": 1280, "height": 800}), ("phone", {"width": 390, "height": 844})):
        context = chromium.new_context(viewport=viewport, is_mobile=size == "phone", has_touch=size == "phone")
        page = context.new_page()
        try:
            log_in(page, exercise_lab, "tutor1")
            page.goto(f"{exercise_lab.url}/exercises/wall-following")
            page.get_by_text("Make it a course's test").click()
            page.get_by_label("Course").select_option(label="Course EX1")
            page.get_by_label("Deadline (UTC)").fill("2100-01-01T12:00")
            page.get_by_label("Points").fill("5000")
            page.get_by_role("button", name="Attach as a test").click()
            status = page.locator("[data-field=attach-status]")
            # The browser holds the form back and says why beside the field (its range is the API's, 0 to 1000).
            assert page.get_by_label("Points").evaluate("field => field.validity.rangeOverflow")
            assert status.inner_text() == ""
            page.get_by_label("Points").fill("7.5" if size == "desktop" else "8")
            page.get_by_role("button", name="Attach as a test").click()
            points = "7.5" if size == "desktop" else "8"
            status.filter(has_text=f"Attached. A test of Course EX1: deadline 2100-01-01 12:00 UTC, {points} points.") \
                .wait_for(timeout=10_000)
            # The course's terms, once: attached again, the new ones replace the old.
            assert page.locator("[data-slot=attached] li").all_inner_texts() == \
                [f"A test of Course EX1: deadline 2100-01-01 12:00 UTC, {points} points."]
            assert page.evaluate("document.documentElement.scrollWidth") <= viewport["width"]
            page.screenshot(path=str(ARTIFACTS_DIR / f"exercise-attach-{size}.png"), full_page=True)
        finally:
            context.close()
    # The student reads the test on the exercise's page, with the terms attached last.
    context = chromium.new_context(viewport={"width": 1280, "height": 800})
    page = context.new_page()
    try:
        log_in(page, exercise_lab)
        page.goto(f"{exercise_lab.url}/exercises/wall-following")
        test = page.locator("[data-field=test]")
        assert "A test of Course EX1: submit before 2100-01-01 12:00 UTC (8.0 points)" in test.inner_text()
        assert page.get_by_text("Make it a course's test").count() == 0  # a student attaches nothing
    finally:
        context.close()


def test_closing_the_tab_stops_the_robot_within_the_deadman_time(chromium, exercise_lab: LiveServer) -> None:
    phone = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    page = phone.new_page()
    try:
        log_in(page, exercise_lab)
        page.goto(f"{exercise_lab.url}/exercises/bump-and-go")
        page.get_by_role("status").filter(has_text="is ready").wait_for(timeout=90_000)
        set_code(page, BUMP_AND_GO)
        page.get_by_role("button", name="Run on my practice robot").click()
        page.get_by_role("status").filter(has_text="Running on").wait_for(timeout=90_000)
        wait_until(lambda: truth_speed(exercise_lab, "practice-student1") > 0.2, 15, "the robot did not move")
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "exercise-phone.png"), full_page=True)
        page.close()
        closed = time.monotonic()
        wait_until(lambda: truth_speed(exercise_lab, "practice-student1", 0.3) < 0.02, 5,
                   "the robot kept moving after its tab closed")
        # The deadman's time (0.4 s) plus the pose log's sampling and this check's own period.
        assert time.monotonic() - closed < 2.0
    finally:
        phone.close()


# The reference line follower (tests/integration/exercises/solutions.py), ending after about a lap, saying so.
LINE_FOLLOWER = ('print("following the line")\n'
                 + solutions.FOLLOW_LINE.replace("while robot.tick():", "while robot.tick() and robot.time() < 44:")
                 + 'print("lap done at", round(robot.time(), 1), "s")\n')
SKILL_CALL = """from telelab import robot

robot.tick()
status = robot.run_skill("orientation_control", heading_rad=1.2)
robot.tick()
print("skill", status, "odometry heading", round(robot.odometry().theta_rad, 2))
"""


def run_program(page, server: LiveServer, slug: str, code: str) -> None:
    """Logs student1 in, opens the exercise, waits for Python, types code and runs it on the practice robot."""
    log_in(page, server)
    page.goto(f"{server.url}/exercises/{slug}")
    page.get_by_role("status").filter(has_text="is ready").wait_for(timeout=90_000)
    set_code(page, code)
    page.get_by_role("button", name="Run on my practice robot").click()


def test_a_student_writes_a_line_follower_runs_it_and_sees_it_graded(page, exercise_lab: LiveServer) -> None:
    log_in(page, exercise_lab)
    page.set_viewport_size({"width": 1280, "height": 900})
    page.goto(f"{exercise_lab.url}/exercises")
    page.get_by_role("link", name="Follow the line").click()
    page.get_by_role("status").filter(has_text="is ready").wait_for(timeout=90_000)
    assert "robot.line_position()" in page.locator(".cm-content").inner_text()  # the template reads the sensor
    set_code(page, LINE_FOLLOWER)
    page.get_by_role("button", name="Run on my practice robot").click()
    page.get_by_role("status").filter(has_text="Running on practice-student1").wait_for(timeout=90_000)
    console = page.locator("[data-field=console]")
    console.filter(has_text="following the line").wait_for(timeout=15_000)
    # The line sensor shows under the editor: placed on the tape, some cell reads it.
    robot = page.locator("[data-field=robot]")
    robot.filter(has_text="line sensor").wait_for(timeout=10_000)
    wait_until(lambda: max(map(float, (robot.get_attribute("data-line") or "0").split())) > 0.5, 10,
               "no cell of the line sensor saw the tape")
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "exercise-line-running.png"), full_page=True)
    console.filter(has_text="lap done").wait_for(timeout=60_000)
    grade = page.locator("[data-field=grade]").filter(has_text="Practice run")
    grade.wait_for(timeout=20_000)
    rows = page.locator("[data-slot=measurements] tbody tr")
    assert rows.count() == 2 and "share of the line followed" in rows.first.inner_text()
    # The browser's loop is the student's own: a lap at 20 Hz in Chromium follows the line as the reference does.
    assert float(grade.get_attribute("data-grade") or 0) == 1.0, grade.inner_text()
    page.locator("[data-slot=map]").scroll_into_view_if_needed()
    page.screenshot(path=str(ARTIFACTS_DIR / "exercise-line-graded.png"), full_page=True)


def test_run_skill_from_the_students_code_runs_the_robots_skill_and_answers_its_status(
        page, exercise_lab: LiveServer) -> None:
    run_program(page, exercise_lab, "bump-and-go", SKILL_CALL)
    console = page.locator("[data-field=console]")
    console.filter(has_text="skill ").wait_for(timeout=60_000)
    assert "skill SUCCEEDED odometry heading" in console.inner_text(), console.inner_text()
    # The robot truly turned to the heading asked (the skill steers by its tracked pose; odometry drifts a little).
    from middleware.robots.registry import robot_registry

    with exercise_lab.app.app_context():
        now = time.time()
        samples = robot_registry().get("practice-student1").pose_log(now - 1.0, now).samples
    assert samples and abs(samples[-1].ground_truth.theta_rad - 1.2) < 0.1, samples[-1].ground_truth


def test_on_a_phone_the_line_sensor_shows_and_a_stopped_run_is_graded(chromium, exercise_lab: LiveServer) -> None:
    phone = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    page = phone.new_page()
    try:
        run_program(page, exercise_lab, "follow-line", LINE_FOLLOWER)
        page.get_by_role("status").filter(has_text="Running on").wait_for(timeout=90_000)
        robot = page.locator("[data-field=robot]")
        robot.filter(has_text="line sensor").wait_for(timeout=15_000)
        wait_until(lambda: float(robot.get_attribute("data-speed") or 0) > 0.1, 15, "the page showed no speed")
        wait_until(lambda: truth_speed(exercise_lab, "practice-student1") > 0.1, 15, "the robot did not move")
        page.screenshot(path=str(ARTIFACTS_DIR / "exercise-line-phone.png"), full_page=True)
        page.get_by_role("button", name="Stop").click()
        grade = page.locator("[data-field=grade]").filter(has_text="Practice run")
        grade.wait_for(timeout=20_000)
        assert "time off the line" in page.locator("[data-slot=measurements]").inner_text(), grade.inner_text()
        assert page.evaluate("document.documentElement.scrollWidth") <= 390  # nothing wider than the phone
        page.screenshot(path=str(ARTIFACTS_DIR / "exercise-line-phone-graded.png"), full_page=True)
    finally:
        phone.close()


SHORT_DRIVE = "from telelab import robot\nwhile robot.tick() and robot.time() < 2:\n    robot.set_velocity(0.2, 0.0)\n"


def test_a_submission_runs_on_a_robot_started_fresh_for_it(page, exercise_lab: LiveServer) -> None:
    from middleware.robots.registry import robot_registry

    def restarts() -> int:
        with exercise_lab.app.app_context():
            return robot_registry().get("practice-student1").health().restarts

    run_program(page, exercise_lab, "bump-and-go", SHORT_DRIVE)
    page.locator("[data-field=grade]").filter(has_text="Practice run").wait_for(timeout=60_000)
    before = restarts()  # practice runs on the robot as it is
    page.get_by_role("button", name="Submit for a grade").click()
    page.locator("[data-field=grade]").filter(has_text="Submission").wait_for(timeout=90_000)
    assert restarts() == before + 1  # the submission's robot is a new process: a fresh world, odometry, battery
    assert page.locator("[data-slot=measurements] tbody tr").count() == 3


def test_the_consoles_line_sensor_panel_reads_the_tape_under_the_robot(page, exercise_lab: LiveServer) -> None:
    from tests.e2e.test_panels import open_console, show_tab_of

    open_console(page, exercise_lab, robot="lab-1")
    page.locator('section[data-panel-id="line-sensor"]').wait_for(state="attached", timeout=20_000)
    show_tab_of(page, "line-sensor")
    panel = page.locator("line-sensor-panel")
    assert panel.locator("[data-line-cell]").count() == 5
    words = panel.locator('[data-field="line-position"]')
    wait_until(lambda: (words.text_content() or "—") != "—", 10, "the line sensor panel showed no reading")
    # lab-1 stands wherever earlier tests left it: over bare floor, or over the tape.
    assert words.text_content() in ("No line under the sensor.", "Line under the middle.") \
        or "cm to the" in (words.text_content() or "")
    panel.screenshot(path=str(ARTIFACTS_DIR / "line-sensor-panel.png"))


# The reference, saying every 5 s what robot.localization() reads while it searches (the journey failed 1 run in 5
# at load, never localized, cause not known: this says which half failed when it fails again).
KIDNAPPED_TELLING_ITS_SEARCH = solutions.KIDNAPPED.replace(
    "where = None\n", "where = None\nsaid_at = 0.0\n", 1).replace("""    robot.set_velocity(0.0, 0.6)
""", """    if robot.time() >= said_at + 5:
        said_at = robot.time()
        print("searching:", None if where is None else (where.converged, round(where.std_m, 2)))
    robot.set_velocity(0.0, 0.6)
""", 1)
assert KIDNAPPED_TELLING_ITS_SEARCH != solutions.KIDNAPPED


def localization_seen(server: LiveServer, robot_name: str) -> str:
    """The robot's localization goal as the skill last said it (its phase, the pose it believes, its figures) beside
    the true pose: whether a cloud that never converged sat on a wrong pose (seen once in a clean-clone run: a tight
    cloud, never converged, for 90 s)."""
    from middleware.robots.registry import robot_registry

    with server.app.app_context():
        link = robot_registry().get(robot_name)
        now = time.time()
        samples = link.pose_log(now - 90.0, now).samples
        goals = [g for g in link.goals() if g.skill == "localization"]
        health = link.health()
    truth = samples[-1].ground_truth if samples else None
    turned = sum(abs(math.remainder(b.ground_truth.theta_rad - a.ground_truth.theta_rad, 2 * math.pi))
                 for a, b in itertools.pairwise(samples))
    faults = [(round(f.unix_s - now, 1), f.kind, f.message) for f in health.faults[-8:]]
    said = [(g.status, g.message, g.feedback.state, round(g.feedback.pose.x_m, 2), round(g.feedback.pose.y_m, 2),
             round(g.feedback.pose.theta_rad, 2), {k: round(v, 3) for k, v in g.feedback.values.items()})
            for g in goals[-1:]]
    true_pose = truth and (round(truth.x_m, 2), round(truth.y_m, 2), round(truth.theta_rad, 2))
    return (f"localization goal {said}, truth {true_pose}; over the last 90 s it truly turned {turned:.1f} rad; the "
            f"robot's loop ran at {health.real_time_factor:.2f} of real time (lag p50 {health.loop_lag_ms_p50:.0f} "
            f"ms); "
            f"faults {faults}; log {list(health.log_tail)[-6:]}")


def test_after_a_kidnapping_the_students_code_localizes_with_the_labs_localization_and_is_graded(
        page, exercise_lab: LiveServer) -> None:
    run_program(page, exercise_lab, "kidnapped", KIDNAPPED_TELLING_ITS_SEARCH)
    console = page.locator("[data-field=console]")
    console.filter(has_text="localization: EXECUTING").wait_for(timeout=60_000)  # start_skill returned at once
    try:
        console.filter(has_text="localized at").wait_for(timeout=90_000)  # robot.localization() converged in Chromium
    except PlaywrightTimeout:  # what the search read meanwhile: no estimate at all, or one that never converged
        raise AssertionError(f"not localized within 90 s; the page's console: {console.inner_text()[-2000:]}; "
                             f"the robot: {localization_seen(exercise_lab, 'practice-student1')}") from None
    grade = page.locator("[data-field=grade]").filter(has_text="Practice run")
    grade.wait_for(timeout=120_000)
    reported = page.locator("[data-slot=measurements] tbody tr").first.inner_text()
    assert "reported pose error" in reported
    # The pose the code reported, graded against where the robot truly stood then (the practice start is known).
    assert float(grade.get_attribute("data-grade") or 0) >= 0.5, grade.inner_text()
    page.locator("[data-slot=map]").scroll_into_view_if_needed()
    page.screenshot(path=str(ARTIFACTS_DIR / "exercise-kidnapped-graded.png"), full_page=True)
