"""Tours in Chromium: the step engine (conditions, pause, replay) and a live class across three browsers."""

from __future__ import annotations

import time

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer

pytestmark = pytest.mark.e2e


def log_in(tab, live_server: LiveServer, username: str) -> None:  # type: ignore[no-untyped-def]
    tab.goto(f"{live_server.url}/login")
    tab.fill("#username", username)
    tab.fill("#password", STUDENT_PASSWORD)
    tab.get_by_role("button", name="Log in").click()
    tab.locator('[data-field="username"]').wait_for()


def test_the_step_engine_conditions_pause_and_replay(page, live_server: LiveServer) -> None:  # type: ignore[no-untyped-def]
    log_in(page, live_server, "student1")
    result = page.evaluate("""async () => {
      const { TourEngine, abortableSleep } = await import('/static/js/tour-engine.js');
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


def test_a_live_class_follows_the_tutor_and_control_is_handed_over(chromium, live_server: LiveServer) -> None:  # type: ignore[no-untyped-def]
    from middleware.access.coordinator import access_coordinator
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.tours.demo import DEMO_TOURS
    from middleware.tours.services import save_tour

    app = live_server.app
    with session_factory(app)() as session:
        create_user(session, "tutor1", "tutor", STUDENT_PASSWORD)
        create_user(session, "student2", "student", STUDENT_PASSWORD)
        tour = save_tour(session, DEMO_TOURS[1], None, None)
        session.commit()
        tour_id = tour.id
        ids = {u.username: u.id for u in session.query(User).all()}
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
        tutor.locator("[data-field=participants]", has_text="student2").wait_for()
        tutor.get_by_role("button", name="Next step").click()
        for student in (first, second):
            student.wait_for_selector("#live[data-step='1']", timeout=5000)
            assert "Go-to-goal plans" in student.text_content("[data-field=step-text]")
        tutor.select_option("[data-field=hand-to]", "student1")
        tutor.get_by_role("button", name="Hand over").click()
        for tab in tabs:
            tab.wait_for_selector("#live[data-controller='student1']", timeout=5000)
        assert first.text_content("[data-field=control]") == "You have control of the robot."
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
