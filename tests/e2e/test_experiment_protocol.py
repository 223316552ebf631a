"""The thesis' protocol as a tutor and a student walk it in Debian's Chromium: the tutor sets the course's learning
period and delays the commands too; the student (on a phone) answers the participant questions once, drives
through the learning period, and begins the first trial of their counterbalanced order, the no-delay control;
the tutor reads the participants as the thesis' table reports them."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, make_course
from tests.e2e.test_console import log_in
from tests.e2e.test_experiment import DESKTOP, PHONE, course_lab

pytestmark = pytest.mark.e2e
LEARNING_MIN = 0.1  # 6 s: long enough to see the countdown, short enough for the suite


def test_a_student_answers_once_learns_for_the_tutors_period_then_starts_the_control_first(
        chromium, tmp_path: Path) -> None:
    with course_lab("course-A", "course-a", tmp_path) as (_robot, lab):
        make_course(lab.app, "EXP", {"tutor1": "tutor", "student1": "student"})
        tutor = chromium.new_context(viewport=DESKTOP).new_page()
        log_in(tutor, lab, "tutor1", STUDENT_PASSWORD)
        tutor.goto(f"{lab.url}/experiment")
        protocol = tutor.locator('form[data-course="EXP"]')
        assert protocol.get_by_label("Learning period (min)").input_value() == "5"  # the thesis' five minutes
        protocol.get_by_label("Learning period (min)").fill("-1")
        protocol.get_by_role("button", name="Save protocol").click()
        assert "learning_s" in (tutor.locator("#experiment-error").text_content() or "") or \
            protocol.get_by_label("Learning period (min)").evaluate("input => !input.validity.valid")
        protocol.get_by_label("Learning period (min)").fill(str(LEARNING_MIN))
        protocol.get_by_label("Delay the commands too (a distant proxy)").check()
        protocol.get_by_role("button", name="Save protocol").click()
        protocol.locator('[data-field="protocol-result"]', has_text="Saved").wait_for()

        student = chromium.new_context(viewport=PHONE).new_page()
        errors: list[str] = []
        student.on("pageerror", lambda error: errors.append(str(error)))
        log_in(student, lab, "student1", STUDENT_PASSWORD)
        student.goto(f"{lab.url}/experiment")
        details = student.locator('[data-field="details"]')
        details.get_by_label("Age").fill("23")
        details.get_by_label("Where you drive from").select_option("remote")
        details.get_by_label("Experience with video games").select_option("some")
        details.get_by_label("Experience with robots").select_option("none")
        details.get_by_label("I agree that these details are kept for the study.").check()
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        student.screenshot(path=str(ARTIFACTS_DIR / "experiment-details-phone.png"), full_page=True)
        details.get_by_role("button", name="Save and continue").click()

        student.get_by_role("button", name="Start the learning period").click()
        countdown = student.locator('[data-field="learning"][data-state="running"]')
        countdown.wait_for()
        assert "left" in (countdown.text_content() or "")
        assert student.get_by_role("link", name="Open course-a's console").is_visible()
        student.screenshot(path=str(ARTIFACTS_DIR / "experiment-learning-phone.png"), full_page=True)
        student.get_by_role("button", name="Start a trial").wait_for(timeout=LEARNING_MIN * 60_000 + 10_000)
        student.reload()
        assert student.locator('[data-field="details"]').count() == 0, "asked once"
        student.get_by_role("button", name="Start a trial").click()
        shown = student.locator('[data-field="condition"]')
        shown.wait_for()
        assert "none (control)" in (shown.text_content() or ""), "the first participant's order begins with the control"
        student.screenshot(path=str(ARTIFACTS_DIR / "experiment-control-trial-phone.png"), full_page=True)

        tutor.reload()
        people = tutor.locator('[data-field="participants"]')
        people.wait_for()
        assert (people.text_content() or "").startswith("1 (1 gave details)")
        assert tutor.locator('[data-field="ages"]').text_content() == "23-23, mean 23.0"
        assert "remote 1" in (tutor.locator('[data-field="location"]').text_content() or "")
        assert (tutor.locator('[data-field="orders"]').text_content() or "").startswith("1 of 10 rows")
        tutor.screenshot(path=str(ARTIFACTS_DIR / "experiment-protocol-tutor-desktop.png"), full_page=True)
        assert errors == []
