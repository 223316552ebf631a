"""Telelab inside an LMS, in Chromium: the LMS's course page (another origin, 127.0.0.1 on another port) frames
the launch; the learner drives the console and submits a placed test inside the frame, and the grade reaches the
LMS's recording AGS endpoint. The same pages framed by an unregistered origin are refused.

Both origins are http://127.0.0.1 (ports differ): same site, so the browser sends Telelab's cookies inside the
frame with no TLS and no third-party-cookie flags; frame-ancestors is per origin, so the refusal is real. Over
HTTPS in production the session cookie is SameSite=None; Secure (tests/integration/lti covers the headers). An LMS
of another site, with third-party cookies blocked and allowed, over HTTPS: test_lti_cross_site.py."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import select

from tests.conftest import ARTIFACTS_DIR, LabClient, LiveServer, served_lab
from tests.integration.lti.conftest import launch, register
from tests.integration.lti.platform import INSTRUCTOR, LEARNER, LmsPlatform

pytestmark = pytest.mark.e2e


@pytest.fixture
def embedded(skill_server_address: str, tmp_path: Path) -> Iterator[tuple[LiveServer, LmsPlatform]]:
    """Telelab with lab-1, and a registered test LMS whose course page frames it."""
    with served_lab(f"lab-1={skill_server_address}", tmp_path) as server:
        lms = LmsPlatform(tool_url=server.url)
        register(server, lms)
        try:
            yield server, lms
        finally:
            lms.stop()


def _placed(server: LiveServer, target: str) -> dict[str, str]:
    from middleware.lti.launches import sign_target

    return {"telelab_target": target, "telelab_sig": sign_target(server.app.config["SECRET_KEY"], "course-1", target)}


def _quiz(server: LiveServer, lms: LmsPlatform) -> int:
    """A one-question test in the LMS course's Telelab course, by its instructor."""
    from middleware.assessment import bank
    from middleware.assessment.schemas import parse_exam, parse_question
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.lti import LtiContext, LtiIdentity

    assert launch(LabClient(server.url), lms, "ines-instructor", [INSTRUCTOR])[0] == 303
    with session_factory(server.app)() as session:
        tutor = session.get(User, session.scalar(select(LtiIdentity.user_id)
                                                 .where(LtiIdentity.subject == "ines-instructor")))
        course_id = session.scalar(select(LtiContext.course_id))
        question = bank.add_question(session, tutor, course_id, parse_question(
            {"kind": "single", "prompt": "Does odometry drift?", "choices": ["No", "Yes"], "correct": 1}))
        exam = bank.create_exam(session, tutor, course_id, parse_exam(
            {"title": "Odometry check", "kind": "quiz", "question_ids": [question.id]}))
        session.commit()
        return exam.id


def _console_number(frame, field: str) -> float:
    text = frame.locator(f'#console [data-field="{field}"]').first.text_content() or ""
    return float(text) if text.strip() not in {"", "—"} else float("nan")


def _wait(predicate, timeout_s: float, message: str) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.1)
    raise AssertionError(message)


def test_a_learner_drives_and_submits_a_test_inside_the_lms_frame_and_the_grade_reaches_the_lms(
        page, embedded: tuple[LiveServer, LmsPlatform]) -> None:
    server, lms = embedded
    exam_id = _quiz(server, lms)
    lms.pending["drive"] = {"sub": "lea-learner", "roles": [LEARNER], "custom": _placed(server, "console:lab-1")}
    lms.pending["quiz"] = {"sub": "lea-learner", "roles": [LEARNER], "custom": _placed(server, f"exam:{exam_id}"),
                           "lineitem": lms.url + "/lineitems/42"}

    page.goto(f"{lms.url}/course?login_hint=drive")
    frame = page.frame_locator("#tool")
    frame.locator('#console[data-robot="lab-1"]').wait_for(timeout=30000)
    frame.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30000)
    _wait(lambda: _console_number(frame, "heading") == _console_number(frame, "heading"), 15, "no odometry arrived")
    # The shared lab robot faces wherever earlier test files left it: the distance moved, not x alone.
    x_before, y_before = _console_number(frame, "x"), _console_number(frame, "y")
    frame.get_by_role("heading", name="Lab 1").click()  # the keys go to the framed page, as a person's would
    page.keyboard.down("ArrowUp")
    _wait(lambda: _console_number(frame, "linear") > 0.05, 10, "the robot did not move inside the LMS's frame")
    time.sleep(0.8)
    page.keyboard.up("ArrowUp")
    _wait(lambda: math.hypot(_console_number(frame, "x") - x_before, _console_number(frame, "y") - y_before) > 0.05,
          5, "odometry did not follow the drive")
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS_DIR / "lti-console-in-lms-frame.png"))

    page.goto(f"{lms.url}/course?login_hint=quiz")
    frame = page.frame_locator("#tool")
    frame.get_by_role("button", name="Start").click(timeout=30000)
    frame.get_by_label("Yes").check()
    frame.locator("#save-status", has_text="Answer saved.").wait_for(state="attached")
    frame.get_by_role("button", name="Submit").click()
    frame.locator("#score").wait_for(timeout=30000)
    page.screenshot(path=str(ARTIFACTS_DIR / "lti-test-in-lms-frame.png"))
    _wait(lambda: len(lms.scores) >= 1, 30, "the grade never reached the LMS's gradebook")
    assert lms.scores[0]["userId"] == "lea-learner" and lms.scores[0]["lineitem"] == "/lineitems/42"
    assert lms.scores[0]["scoreGiven"] == lms.scores[0]["scoreMaximum"] == 1

    page.set_viewport_size({"width": 390, "height": 844})
    page.goto(f"{lms.url}/course?login_hint=quiz")
    page.frame_locator("#tool").get_by_role("button", name="Start").wait_for(timeout=30000)
    page.screenshot(path=str(ARTIFACTS_DIR / "lti-test-in-lms-frame-phone.png"))


def test_an_instructor_places_a_test_from_the_lms_and_an_admin_registers_an_lms(
        page, embedded: tuple[LiveServer, LmsPlatform]) -> None:
    server, lms = embedded
    from middleware.db import session_factory

    _quiz(server, lms)
    lms.pending["place"] = {"sub": "ines-instructor", "roles": [INSTRUCTOR], "deep_link": True}
    page.goto(f"{lms.url}/course?login_hint=place")
    frame = page.frame_locator("#tool")
    frame.get_by_label("Odometry check").check(timeout=30000)
    frame.get_by_label("lab-1").check()
    page.screenshot(path=str(ARTIFACTS_DIR / "lti-deep-link-picker.png"))
    frame.get_by_role("button", name="Place in the LMS course").click()
    frame.locator("#placed").wait_for(timeout=30000)  # the LMS's page: the answer came back, signed
    items = lms.deep_link_returns[-1]["https://purl.imsglobal.org/spec/lti-dl/claim/content_items"]
    assert sorted(item["title"] for item in items) == ["Odometry check", "lab-1"]

    # The tutor's course page has the LMS card: roster sync, grades sent and waiting.
    from middleware.models.lti import LtiContext

    with session_factory(server.app)() as session:
        course_id = session.scalar(select(LtiContext.course_id))
    page.goto(f"{server.url}/courses/{course_id}")
    page.locator("#lms-panel").get_by_role("button", name="Sync the roster from the LMS").wait_for()
    page.locator("#lms-panel").screenshot(path=str(ARTIFACTS_DIR / "lti-course-card-desktop.png"))
    page.set_viewport_size({"width": 390, "height": 844})
    page.locator("#lms-panel").screenshot(path=str(ARTIFACTS_DIR / "lti-course-card-phone.png"))

    from tests.conftest import STUDENT_PASSWORD, add_test_account

    with session_factory(server.app)() as session:
        add_test_account(session, "admin1", "admin")
        session.commit()
    admin = page.context.browser.new_context(viewport={"width": 390, "height": 844}).new_page()
    admin.goto(f"{server.url}/login")
    admin.fill("#username", "admin1")
    admin.fill("#password", STUDENT_PASSWORD)
    admin.get_by_role("button", name="Log in").click()
    admin.goto(f"{server.url}/admin/lti")
    assert admin.locator('[data-field="login_url"]').text_content() == f"{server.url}/lti/login"
    admin.get_by_label("Issuer (platform id)").fill("moodle.example.edu")
    admin.get_by_role("button", name="Register").click()
    assert "must be a full address" in admin.locator('[data-error-for="issuer"]').text_content()
    admin.get_by_label("Issuer (platform id)").fill("https://moodle.example.edu")
    admin.get_by_label("Client id").fill("abc123")
    admin.get_by_label("Deployment ids").fill("1")
    admin.get_by_label("Authentication request URL").fill("https://moodle.example.edu/mod/lti/auth.php")
    admin.get_by_label("Access token URL").fill("https://moodle.example.edu/mod/lti/token.php")
    admin.get_by_label("Public keyset (JWKS) URL").fill("https://moodle.example.edu/mod/lti/certs.php")
    admin.get_by_role("button", name="Register").click()
    admin.locator("#platforms", has_text="https://moodle.example.edu").wait_for()
    admin.screenshot(path=str(ARTIFACTS_DIR / "lti-admin-phone.png"), full_page=True)
    admin.set_viewport_size({"width": 1280, "height": 800})
    admin.screenshot(path=str(ARTIFACTS_DIR / "lti-admin-desktop.png"), full_page=True)
    admin.context.close()


def test_an_unregistered_origin_cannot_frame_telelab(page, embedded: tuple[LiveServer, LmsPlatform]) -> None:
    server, lms = embedded
    stranger = LmsPlatform(tool_url=server.url)  # serves the same framing page, but is not registered
    try:
        stranger.pending["x"] = {"sub": "x", "roles": [LEARNER]}
        refused: list[str] = []
        page.on("console", lambda message: refused.append(message.text) if "frame-ancestors" in message.text else None)
        page.goto(f"{stranger.url}/course?login_hint=x")
        _wait(lambda: bool(refused), 15, "the browser framed Telelab for an unregistered origin")
        frame = page.frame_locator("#tool")
        assert frame.locator("#login-check").count() == 0  # nothing of Telelab's page is shown
        lms.pending["x"] = {"sub": "x-learner", "roles": [LEARNER]}
        page.goto(f"{lms.url}/course?login_hint=x")  # the registered LMS is let in
        page.frame_locator("#tool").locator('a.robot-card[data-robot="lab-1"]').wait_for(timeout=30000)
    finally:
        stranger.stop()
    # A learner's deep-linking launch is refused, in words, inside the frame.
    lms.pending["bad"] = {"sub": "x-learner", "roles": [LEARNER], "deep_link": True}
    page.set_viewport_size({"width": 390, "height": 844})
    page.goto(f"{lms.url}/course?login_hint=bad")
    heading = page.frame_locator("#tool").get_by_role("heading", name="Telelab could not open this launch from the LMS")
    heading.wait_for(timeout=30000)
    assert "instructors" in page.frame_locator("#tool").locator("#error-message").text_content()
    page.screenshot(path=str(ARTIFACTS_DIR / "lti-refused-in-lms-frame-phone.png"))


def test_an_exercise_framed_by_the_lms_offers_a_window_of_its_own_where_python_runs(
        page, embedded: tuple[LiveServer, LmsPlatform]) -> None:
    """Deep linking asks the LMS to open an exercise in a window (tests/integration/lti/test_deep_link_kinds.py); an
    LMS that frames it anyway gets a page that loads (the LMS may frame it) and says why it needs a window."""
    server, lms = embedded
    lms.pending["code"] = {"sub": "lea-learner", "roles": [LEARNER], "custom": _placed(server, "exercise:bump-and-go")}
    page.goto(f"{lms.url}/course?login_hint=code")
    frame = page.frame_locator("#tool")
    notice = frame.locator("[data-slot=own-window]")
    notice.wait_for(timeout=30000)
    assert "a window of their own" in notice.inner_text()
    page.screenshot(path=str(ARTIFACTS_DIR / "lti-exercise-in-lms-frame.png"))
    with page.context.expect_page() as opened:
        notice.get_by_role("link", name="Open in a new window").click()
    window = opened.value
    window.get_by_role("status").filter(has_text="is ready").wait_for(timeout=90_000)  # isolated: Pyodide runs
    assert window.locator("[data-slot=own-window]").is_hidden()
    window.close()
