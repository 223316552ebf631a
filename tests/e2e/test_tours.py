"""Tours in Chromium: the step engine (conditions, pause, replay) and a live class across three browsers."""

from __future__ import annotations

import re
import time

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer, make_course
from tests.e2e.test_panels import wait_for

pytestmark = pytest.mark.e2e


def log_in(tab, live_server: LiveServer, username: str) -> None:
    tab.goto(f"{live_server.url}/login")
    tab.fill("#username", username)
    tab.fill("#password", STUDENT_PASSWORD)
    tab.get_by_role("button", name="Log in").click()
    tab.locator('[data-field="username"]').wait_for()


def book_class_slot_now(app, course_id: int, tutor: str) -> None:
    """A class booking of tutor on lab-1 from a minute ago for half an hour."""
    from datetime import UTC, datetime, timedelta

    from middleware.db import session_factory
    from middleware.models import Booking, User

    now = datetime.now(UTC)
    with session_factory(app)() as session:
        user_id = session.query(User).filter_by(username=tutor).one().id
        session.add(Booking(robot_name="lab-1", user_id=user_id, course_id=course_id, kind="class",
                            starts_at=now - timedelta(minutes=1), ends_at=now + timedelta(minutes=30)))
        session.commit()


def test_the_step_engine_conditions_pause_and_replay(page, live_server: LiveServer) -> None:
    log_in(page, live_server, "student1")
    result = page.evaluate("""async () => {
      const { TourEngine, abortableSleep } = await import('/static/pages/teaching/tour-engine.js');
      const seen = [];
      let finishGoal;
      const steps = [
        { text: 'a', panel: 'camera', condition: { type: 'time', seconds: 0.05 } },
        { text: 'b', panel: 'map', command: { skill: 'go_to_goal' }, condition: { type: 'skill_finished' } },
        { text: 'c', panel: 'drive', condition: { type: 'manual' } },
      ];
      const io = {
        show: (i) => seen.push(`show ${i}`),
        run: async (i) => { seen.push(`run ${i}`); return 'g' + i; },
        waitGoal: (id, signal) => new Promise((resolve, reject) => {
          finishGoal = resolve;
          signal.addEventListener('abort', () => reject(new DOMException('x', 'AbortError')));
        }),
        sleep: abortableSleep,
        stop: async () => seen.push('stop'),
        changed: (s) => seen.push(`${s.status} ${s.index}`),
      };
      const engine = new TourEngine(steps, io);
      const tick = (ms) => new Promise((r) => setTimeout(r, ms));
      engine.start();
      await tick(200);                      // step 0 waited its time; step 1 waits for its goal
      const waitingOnGoal = engine.state;
      await engine.pause();                 // pause: the robot stops, the wait ends
      const paused = engine.state;
      finishGoal?.('succeeded');            // a stale goal end changes nothing
      await tick(20);
      engine.resume();                      // replays step 1
      await tick(50);
      finishGoal('succeeded');
      await tick(50);
      const manual = engine.state;          // step 2 waits for Next
      await engine.next();
      const done = engine.state;
      engine.replay();
      await tick(20);
      return { seen, waitingOnGoal, paused, manual, done, replayed: engine.state };
    }""")
    assert result["waitingOnGoal"]["index"] == 1 and result["waitingOnGoal"]["status"] == "waiting"
    assert result["paused"]["status"] == "paused"
    assert result["manual"] == {"index": 2, "status": "waiting", "message": "", "count": 3}
    assert result["done"]["status"] == "done"
    assert result["replayed"]["index"] == 0
    seen = result["seen"]
    assert seen[:4] == ["show 0", "running 0", "waiting 0", "show 1"]
    assert seen.count("run 1") == 2 and "stop" in seen  # step 1 ran again after the pause


def test_a_live_class_follows_the_tutor_and_control_is_handed_over(chromium, live_server: LiveServer) -> None:
    from middleware.access.coordinator import access_coordinator
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.teaching.demo_content import DEMO_TOURS
    from middleware.teaching.tours import save_tour

    app = live_server.app
    with session_factory(app)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        create_user(session, "outsider", "student", STUDENT_PASSWORD)
        tour = save_tour(session, DEMO_TOURS[1], None, None)
        session.commit()
        tour_id = tour.id
        ids = {u.username: u.id for u in session.query(User).all()}
    # The class goes before the queue (and can hand the robot to a student) only in its tutor's booked slot.
    book_class_slot_now(app, make_course(app, "ROB1", {"tutor1": "tutor", "student1": "student",
                                                       "student2": "student"}), "tutor1")
    contexts = [chromium.new_context(viewport=size) for size in
                ({"width": 1280, "height": 800}, {"width": 1280, "height": 800}, {"width": 390, "height": 844})]
    errors: list[str] = []
    tabs = []
    try:
        for context, name in zip(contexts, ("tutor1", "student1", "student2"), strict=True):
            tab = context.new_page()
            tab.on("pageerror", lambda error: errors.append(str(error)))
            log_in(tab, live_server, name)
            tabs.append(tab)
        tutor, first, second = tabs
        tutor.goto(f"{live_server.url}/tours/{tour_id}/lead")
        tutor.get_by_role("button", name="Start the class").click()
        tutor.wait_for_url("**/tours/sessions/*")
        session_path = tutor.url.split(live_server.url, 1)[1]
        for student in (first, second):
            student.goto(live_server.url + session_path)
            student.wait_for_selector("#live[data-step='0']")
        outsider = contexts[2].browser.new_context(viewport={"width": 390, "height": 844})  # type: ignore[union-attr]
        contexts.append(outsider)
        stranger = outsider.new_page()
        log_in(stranger, live_server, "outsider")
        stranger.goto(live_server.url + session_path)
        stranger.get_by_text("This class is for the students of another course.").wait_for()
        assert stranger.locator("#live").count() == 0
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        stranger.screenshot(path=str(ARTIFACTS_DIR / "tour-live-outsider-390.png"))
        tutor.locator("[data-field=participants]", has_text="student2").wait_for()
        tutor.get_by_role("button", name="Next step").click()
        for student in (first, second):
            student.wait_for_selector("#live[data-step='1']", timeout=5000)
            assert "Go-to-goal plans" in student.text_content("[data-field=step-text]")
            student.locator("[data-field=step-panel]", has_text="Go to goal").wait_for(timeout=15_000)
        tutor.select_option("[data-field=hand-to]", "student1")
        tutor.get_by_role("button", name="Hand over").click()
        for tab in tabs:
            tab.wait_for_selector("#live[data-controller='student1']", timeout=5000)
        assert first.text_content("[data-field=control]") == "You have control of the robot."
        pad = first.get_by_role("region", name="Drive", exact=True)
        assert pad.is_visible() and first.get_by_role("region", name="Camera", exact=True).is_visible()
        deadline = time.monotonic() + 10
        while access_coordinator(app).controller_token("lab-1", ids["student1"]) is None:
            assert time.monotonic() < deadline, "the access rule did not give student1 the robot"
            time.sleep(0.2)
        tutor.get_by_role("button", name="Take it back").click()
        for tab in tabs:
            tab.wait_for_selector("#live[data-controller='tutor1']", timeout=5000)
        deadline = time.monotonic() + 10
        while access_coordinator(app).controller_token("lab-1", ids["tutor1"]) is None:
            assert time.monotonic() < deadline, "the tutor did not get the robot back"
            time.sleep(0.2)
        second.fill("#question", "<b>why</b> does it stop?")
        second.get_by_role("button", name="Send").click()
        tutor.locator("[data-slot=chat] li", has_text="<b>why</b> does it stop?").wait_for()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        tutor.screenshot(path=str(ARTIFACTS_DIR / "tour-live-tutor-1280.png"), full_page=True)
        second.screenshot(path=str(ARTIFACTS_DIR / "tour-live-student-390.png"), full_page=True)
        tutor.get_by_role("button", name="End the class").click()
        first.locator("[data-field=control]", has_text="The class has ended.").wait_for()
    finally:
        for context in contexts:
            context.close()
    assert not errors, errors


def test_only_a_tutor_of_the_course_can_start_its_live_class(chromium, live_server: LiveServer) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.models.teaching import GuidedSession
    from middleware.teaching.demo_content import DEMO_TOURS
    from middleware.teaching.tours import save_tour

    app = live_server.app
    with session_factory(app)() as session:
        for name in ("tutor1", "tutor2", "tutor3"):
            create_user(session, name, "tutor", STUDENT_PASSWORD)
        tour_id = save_tour(session, DEMO_TOURS[1], None, None).id
        session.commit()
    course_a = make_course(app, "ROB-A", {"tutor1": "tutor", "student1": "student"})
    make_course(app, "ROB-B", {"tutor2": "tutor"})
    context = chromium.new_context(viewport={"width": 1280, "height": 800})
    errors: list[str] = []
    try:
        other = context.new_page()
        other.on("pageerror", lambda error: errors.append(str(error)))
        log_in(other, live_server, "tutor2")
        other.goto(f"{live_server.url}/tours/{tour_id}/lead")
        choices = other.locator("select[name=course_id] option").all_text_contents()
        assert choices == ["Course ROB-B"]  # neither course A nor "no course"
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        other.screenshot(path=str(ARTIFACTS_DIR / "class-lead-other-course-tutor-1280.png"), full_page=True)
        refused = other.evaluate("""async ([tour, course]) => {
          const { fetchJson } = await import('/static/lib/transport.js');
          try {
            const body = { robot: 'lab-1', course_id: course };
            await fetchJson(`/api/tours/${tour}/sessions`, { method: 'POST', body });
            return 'started';
          } catch (error) { return `${error.status} ${error.message}`; }
        }""", [tour_id, course_a])
        assert refused == "403 You can lead classes only for the courses you teach."
        with session_factory(app)() as session:
            assert session.query(GuidedSession).count() == 0
        context.clear_cookies()

        unassigned = context.new_page()  # tutor3 teaches no course yet
        unassigned.on("pageerror", lambda error: errors.append(str(error)))
        log_in(unassigned, live_server, "tutor3")
        unassigned.goto(f"{live_server.url}/tours/{tour_id}/lead")
        assert "You teach no course yet" in unassigned.text_content("[data-field=no-course]")
        assert unassigned.get_by_role("button", name="Start the class").count() == 0
        unassigned.screenshot(path=str(ARTIFACTS_DIR / "class-lead-tutor-of-no-course-1280.png"), full_page=True)
        context.clear_cookies()

        own = context.new_page()
        own.on("pageerror", lambda error: errors.append(str(error)))
        log_in(own, live_server, "tutor1")
        own.goto(f"{live_server.url}/tours/{tour_id}/lead")
        assert own.locator("select[name=course_id] option").all_text_contents() == ["Course ROB-A"]
        own.screenshot(path=str(ARTIFACTS_DIR / "class-lead-own-tutor-1280.png"), full_page=True)
        own.get_by_role("button", name="Start the class").click()
        own.wait_for_url("**/tours/sessions/*")
        own.wait_for_selector("#live[data-step='0']")
        own.screenshot(path=str(ARTIFACTS_DIR / "class-started-by-own-tutor-1280.png"), full_page=True)
        with session_factory(app)() as session:
            started = session.query(GuidedSession).one()
            assert started.course_id == course_a and started.ended_at is None
    finally:
        context.close()
    assert not errors, errors


@pytest.mark.parametrize("size", [{"width": 1280, "height": 800}, {"width": 390, "height": 844}])
def test_a_tour_shows_the_panels_it_names_by_their_titles(chromium, live_server: LiveServer, size) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.teaching.demo_content import DEMO_TOURS
    from middleware.teaching.practice_robots import practice_manager
    from middleware.teaching.tours import save_tour

    with session_factory(live_server.app)() as session:
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        tour_id = save_tour(session, DEMO_TOURS[1], None, None).id  # Go to a goal: map, skill-go_to_goal, odometry
        session.commit()
    context = chromium.new_context(viewport=size)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        log_in(page, live_server, "student2")
        page.goto(f"{live_server.url}/tours/{tour_id}")
        page.get_by_role("button", name="Start the tour").click()
        page.locator("[data-field=step-panel]", has_text="Lab model").wait_for(timeout=60_000)
        for title in ("Camera", "Lab model", "Go to goal", "Odometry"):
            assert page.get_by_role("region", name=title, exact=True).count() == 1, title
        assert page.get_by_role("region", name="Sonar", exact=True).count() == 0
        current = page.locator(".panel-frame--current")
        assert current.get_attribute("data-panel-id") == "map"
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / f"tour-panels-{size['width']}.png"), full_page=True)
        page.locator("[data-field=step-panel]", has_text="Go to goal").wait_for(timeout=15_000)
        assert page.locator(".panel-frame--current").get_attribute("data-panel-id") == "skill-go_to_goal"
        assert "max_error_m" not in page.locator("#tour").text_content()
        # The panel the step points at comes into view and shows the tour's goal, not Idle (issue 34, item 15).
        skill = page.locator('skill-panel[data-skill="go_to_goal"]')
        skill.locator('[data-field="skill-status"]').filter(has_text=re.compile(r"^(Running|Succeeded)$")).wait_for(
            timeout=10_000)
        wait_for(lambda: in_view(page, ".panel-frame--current"), 5, "the step's panel is not on the screen: "
                 + str(page.locator(".panel-frame--current").evaluate(
                     "(e) => [e.getBoundingClientRect().top, e.getBoundingClientRect().height, innerHeight, scrollY]")))
        page.screenshot(path=str(ARTIFACTS_DIR / f"tour-step-panel-in-view-{size['width']}.png"))
    finally:
        context.close()
        practice_manager(live_server.app).shutdown()
    assert not errors, errors


def in_view(page, selector: str) -> bool:
    """Whether the element's top (its title) is on the screen."""
    return page.locator(selector).evaluate(
        "(e) => { const r = e.getBoundingClientRect(); return r.top >= 0 && r.top + 40 <= innerHeight; }")


def test_the_tour_editor_offers_panels_by_their_titles(page, live_server: LiveServer) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory

    with session_factory(live_server.app)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        session.commit()
    log_in(page, live_server, "tutor1")
    page.goto(f"{live_server.url}/tours/new")
    panel = page.get_by_label("Panel to look at")
    options = panel.locator("option").all_text_contents()
    assert "Lab model" in options and "Go to goal" in options
    page.get_by_label("Title", exact=True).first.fill("Look around")
    page.get_by_label("Text").fill("The lab from above.")
    panel.select_option(label="Lab model")
    page.get_by_label("Go on when").select_option("manual")
    page.get_by_role("button", name="Add the step").click()
    assert '"panel": "map"' in page.locator("[name=steps]").input_value()
    # The second step runs a skill, built from its schema's fields instead of typed JSON.
    page.get_by_label("Step title").fill("Drive to the door")
    page.get_by_label("Text").fill("Watch the planned path.")
    panel.select_option(label="Lab model")
    page.get_by_label("What the robot does").select_option("skill")
    page.get_by_label("Skill", exact=True).select_option(label="Go to goal")
    page.get_by_label("Goal x").fill("1")
    page.get_by_label("Goal y").fill("0.5")
    page.get_by_label("Go on when").select_option("skill_finished")
    page.get_by_role("button", name="Add the step").click()
    steps = page.locator('[data-slot="step-list"] li')
    assert steps.count() == 2
    second = steps.nth(1).inner_text()
    assert "Drive to the door" in second and "look at Lab model" in second, second
    assert "Go to goal: goal x 1 m, goal y 0.5 m" in second and "goes on when the skill finishes" in second, second
    page.get_by_role("button", name="Move step 2 up").click()
    assert "Drive to the door" in steps.nth(0).inner_text()
    page.get_by_role("button", name="Save").click()
    page.wait_for_url(re.compile(r"/tours/\d+/edit$"))  # a new tour opens in its own editor once saved
    assert page.locator('[data-slot="step-list"] li').count() == 2
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "tour-editor-1280.png"), full_page=True)
    page.set_viewport_size({"width": 390, "height": 844})
    page.screenshot(path=str(ARTIFACTS_DIR / "tour-editor-390.png"), full_page=True)
