"""The catalogue's form in Chromium (issue 32): a tutor writes a new exercise with it, reads the API's refusal beside
the field it names (a time limit of 0), fixes it and saves; a student opens the new exercise and reads its statement
and template; an edit changes the statement; the rubric's numbers follow the chosen kind; a student sees no "New
exercise" and is refused the form. In English and Spanish, at desktop and phone sizes (test-artifacts/
exercise-form-*.png). No robot runs here: the form and the pages it leads to need none."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer, served_lab
from tests.e2e.test_exercises import set_code
from tests.e2e.test_lessons import log_in
from tests.e2e.test_spanish import log_in as log_in_spanish

pytestmark = pytest.mark.e2e

DESKTOP = {"width": 1280, "height": 800}
PHONE = {"width": 375, "height": 812}
TEMPLATE = "from telelab import robot\n\n# Drive to the crate.\nwhile robot.tick():\n    robot.set_velocity(0.2, 0.0)\n"


@pytest.fixture(scope="module")
def form_lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    with served_lab("lab-1=127.0.0.1:9", tmp_path_factory.mktemp("exercise-form")) as server:
        yield server


def tab(chromium, size: str, locale: str = "en-GB"):
    context = chromium.new_context(viewport=DESKTOP if size == "desktop" else PHONE, locale=locale,
                                   is_mobile=size == "phone", has_touch=size == "phone")
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    return context, page, errors


def open_new_form(page, server: LiveServer, log_in_as, link: str) -> None:
    """The tutor opens the form from the exercises' list, by its link (link: its name in the page's language)."""
    log_in_as(page, server, "tutor1")
    page.goto(f"{server.url}/exercises")
    page.get_by_role("link", name=link).click()
    page.locator("#exercise-form[data-ready]").wait_for()


def fits(page) -> None:
    overflow = page.evaluate("document.documentElement.scrollWidth - window.innerWidth")
    assert overflow <= 1, f"the page scrolls sideways by {overflow} px"


@pytest.mark.parametrize("size", ["desktop", "phone"])
def test_a_tutor_writes_an_exercise_reads_a_refusal_beside_its_field_and_a_student_opens_it(
        chromium, form_lab: LiveServer, size: str) -> None:
    slug = f"reach-the-crate-{size}"
    context, page, errors = tab(chromium, size)
    try:
        open_new_form(page, form_lab, log_in, "New exercise")
        page.get_by_label("Title").fill(f"Reach the crate {size}")
        # The address name follows the title until the tutor writes one.
        assert page.get_by_label("Address name").input_value() == slug
        page.get_by_label("Statement").fill("Drive to the crate at x = 2 m, y = 1.4 m.")
        set_code(page, TEMPLATE)
        page.get_by_label("Rubric", exact=True).select_option("reach_goal")
        numbers = page.locator("fieldset[data-kind=reach_goal]")
        numbers.get_by_label("Goal, x").fill("2")
        numbers.get_by_label("Goal, y").fill("1.4")
        numbers.get_by_label("Goal radius").fill("0.4")
        page.get_by_label("Submissions start at random in a hidden region").check()
        for label, value in (("Smallest x", "-0.5"), ("Largest x", "0.5"), ("Smallest y", "-0.5"),
                             ("Largest y", "0.5"), ("Smallest heading", "-1"), ("Largest heading", "1")):
            page.locator("[data-slot=region]").get_by_label(label).fill(value)
        time_limit = page.get_by_label("Time limit")
        time_limit.fill("0")
        # The form is walked by keyboard: Tab from the title reaches the address name, the statement, the editor,
        # and Tab leaves the editor for the scene (the editor does not keep Tab).
        page.get_by_label("Title").focus()
        for expected in ("f-slug", "f-statement"):
            page.keyboard.press("Tab")
            assert page.evaluate("document.activeElement.id") == expected
        page.keyboard.press("Tab")
        assert page.evaluate("document.activeElement.classList.contains('cm-content')")
        page.keyboard.press("Tab")
        assert page.evaluate("document.activeElement.id") == "f-scene"
        page.get_by_role("button", name="Save the exercise").click()

        # The API's refusal, beside the time limit, which has the focus; the status line says it too.
        error = page.locator("#f-time-limit-error")
        error.wait_for()
        assert "time_limit_s must be between 5 and 600" in error.inner_text()
        assert time_limit.get_attribute("aria-invalid") == "true"
        assert "f-time-limit-error" in (time_limit.get_attribute("aria-describedby") or "")
        assert page.evaluate("document.activeElement.id") == "f-time-limit"
        assert page.locator("[data-field=form-status]").inner_text() == \
            f"Not saved. Time limit: {error.inner_text()}"
        fits(page)
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / f"exercise-form-refused-{size}.png"), full_page=True)
        page.keyboard.press("Control+a")
        page.keyboard.type("30")
        page.keyboard.press("Enter")  # Enter in a field submits the form, as any form
        saved = page.locator("[data-field=form-status] [data-kind=saved]")
        saved.wait_for()
        assert saved.inner_text().startswith(f"Saved “Reach the crate {size}” ({slug}): Reach a goal"), \
            saved.inner_text()
        assert "time limit 30 s" in saved.inner_text()
        assert error.is_hidden() and time_limit.get_attribute("aria-invalid") is None
        assert page.url.endswith(f"/exercises/{slug}/edit")
        page.screenshot(path=str(ARTIFACTS_DIR / f"exercise-form-saved-{size}.png"), full_page=True)

        # Saved again from the same page: now it rewrites it (PUT), with the new statement.
        page.get_by_label("Statement").fill("Drive to the wooden crate at x = 2 m, y = 1.4 m.")
        page.get_by_role("button", name="Save the exercise").click()
        saved.filter(has_text="Saved").wait_for()
        page.locator("[data-field=saved-link]").click()
        page.locator(".exercise-statement").filter(has_text="wooden crate").wait_for()
        assert page.get_by_role("link", name="Edit this exercise").get_attribute("href") == \
            f"/exercises/{slug}/edit"  # a tutor's way back to the form from the exercise itself

        # The list offers Edit on it, and the form opens with what was saved, the hidden region too.
        page.goto(f"{form_lab.url}/exercises")
        page.get_by_role("link", name=f"Edit Reach the crate {size}").click()
        page.locator("#exercise-form[data-ready]").wait_for()
        assert page.get_by_label("Time limit").input_value() == "30"
        assert page.locator("[data-slot=region]").get_by_label("Largest heading").input_value() == "1"
        assert page.locator("fieldset[data-kind=reach_goal]").get_by_label("Goal radius").input_value() == "0.4"
        assert page.get_by_label("Address name").count() == 0  # an exercise's address does not change
        page.get_by_label("Statement").fill("Drive to the red crate at x = 2 m, y = 1.4 m.")
        page.get_by_role("button", name="Save the exercise").click()
        page.locator("[data-field=form-status] [data-kind=saved]").wait_for()
        fits(page)
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"

    # The student opens it from the list and reads the edited statement and the template in the editor.
    context, page, errors = tab(chromium, size)
    try:
        log_in(page, form_lab, "student1")
        page.goto(f"{form_lab.url}/exercises")
        assert page.get_by_role("link", name="New exercise").count() == 0
        assert page.locator("a[href$='/edit']").count() == 0
        page.get_by_role("link", name=f"Reach the crate {size}").click()
        assert "Drive to the red crate at x = 2 m, y = 1.4 m." in page.locator(".exercise-statement").inner_text()
        page.locator(".cm-content").filter(has_text="Drive to the crate.").wait_for(timeout=30_000)
        assert "robot.set_velocity(0.2, 0.0)" in page.locator(".cm-content").inner_text()
        assert page.locator("a[href$='/edit']").count() == 0  # nor on the exercise's own page
        page.screenshot(path=str(ARTIFACTS_DIR / f"exercise-form-student-reads-{size}.png"), full_page=True)
        for path in ("/exercises/new", f"/exercises/{slug}/edit"):
            answer = page.goto(f"{form_lab.url}{path}")
            assert answer is not None and answer.status == 403, path
            assert page.get_by_text("Only tutors and admins change the exercise catalogue.").count() == 1
    finally:
        context.close()


def test_the_rubrics_numbers_follow_its_kind_and_a_refusal_names_the_chosen_kinds_field(
        chromium, form_lab: LiveServer) -> None:
    context, page, errors = tab(chromium, "desktop")
    try:
        log_in(page, form_lab, "tutor1")
        page.goto(f"{form_lab.url}/exercises/follow-line/edit")
        page.locator("#exercise-form[data-ready]").wait_for()
        shown = page.locator("fieldset[data-kind]:visible")
        assert shown.count() == 1 and shown.get_attribute("data-kind") == "follow_line"
        assert shown.get_by_label("Corners' radius").input_value() == "0.45"
        assert "(0 to 1)" in shown.locator("label[for=f-rubric-follow_line-min_covered]").inner_text()
        page.get_by_label("Rubric", exact=True).select_option("bump_and_go")
        shown = page.locator("fieldset[data-kind]:visible")
        assert shown.get_attribute("data-kind") == "bump_and_go"
        labels = [label.inner_text() for label in shown.locator("label").all()]
        assert labels == ["Distance to drive (m)", "Floor cells to visit (cells)", "Longest time stuck (s)",
                          "Floor cell size (m)", "Stuck radius (m)"], labels
        assert "left empty, the grader takes 0.5 m" in shown.locator("#f-rubric-bump_and_go-cell_m-hint").inner_text()
        shown.get_by_label("Distance to drive").fill("6")
        shown.get_by_label("Longest time stuck").fill("5")
        page.get_by_role("button", name="Save the exercise").click()
        # The bump-and-go numbers are the ones checked, and the one left empty is named, under its box.
        error = page.locator("#f-rubric-bump_and_go-min_cells-error")
        error.wait_for()
        assert "rubric.min_cells must be a finite number" in error.inner_text()
        page.screenshot(path=str(ARTIFACTS_DIR / "exercise-form-rubric-refused-desktop.png"), full_page=True)
        # A refusal naming a group (the region's x range) is shown under its first box; the one before is cleared.
        shown.get_by_label("Floor cells to visit").fill("14")
        region = page.locator("[data-slot=region]")
        region.get_by_label("Smallest x").fill("2")
        page.get_by_role("button", name="Save the exercise").click()
        region_error = page.locator("#f-region-x-low-error")
        region_error.wait_for()
        assert "random_starts.x_m: low must not exceed high" in region_error.inner_text()
        assert error.is_hidden()
        assert page.evaluate("document.activeElement.id") == "f-region-x-low"
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"


@pytest.mark.parametrize("size", ["desktop", "phone"])
def test_the_form_speaks_spanish(chromium, form_lab: LiveServer, size: str) -> None:
    context, page, errors = tab(chromium, size, "es-ES")
    try:
        open_new_form(page, form_lab, log_in_spanish, "Nuevo ejercicio")
        page.get_by_label("Título").fill(f"Llega a la caja {size}")
        page.get_by_label("Límite de tiempo").fill("0")
        page.get_by_role("button", name="Guardar el ejercicio").click()
        # The rubric's goal, left empty, is the first field the API refuses: beside it, in Spanish.
        error = page.locator("#f-rubric-reach_goal-x_m-error")
        error.wait_for()
        assert "debe ser un número finito" in error.inner_text(), error.inner_text()
        status = page.locator("[data-field=form-status]").inner_text()
        assert status.startswith("No se guardó."), status
        fits(page)
        page.screenshot(path=str(ARTIFACTS_DIR / f"exercise-form-spanish-{size}.png"), full_page=True)
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"
