"""The admin's pool form in Chromium, given what a paste can put in its "How many" box (a superscript digit, 5 000
digits): the form comes back with a sentence under the box, at desktop and phone sizes, never an error page."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, served_lab
from tests.e2e.test_lessons import log_in

pytestmark = pytest.mark.e2e


@pytest.mark.parametrize(("viewport", "count"), [((1280, 800), "²"), ((390, 844), "1" * 5000)])
def test_a_pasted_count_that_is_no_number_is_refused_under_its_box(chromium, tmp_path, viewport, count) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory

    with served_lab("lab-1=127.0.0.1:9", tmp_path) as server:
        with session_factory(server.app)() as session:
            create_user(session, "root", "admin", STUDENT_PASSWORD)
            session.commit()
        context = chromium.new_context(viewport={"width": viewport[0], "height": viewport[1]})
        page = context.new_page()
        try:
            log_in(page, server, "root")
            page.goto(f"{server.url}/admin/pools")
            form = page.locator("#start-pool-form")
            form.get_by_label("Kind").fill("sim")
            form.get_by_label("How many").fill(count)
            form.get_by_role("button", name="Start robots").click()
            error = page.locator('[data-error-for="count"]')
            error.wait_for()
            assert error.inner_text() == "count must be a whole number from 1 to 50."
            assert page.get_by_role("heading", name="Robot pools").is_visible()
            assert form.get_by_label("Kind").input_value() == "sim"  # what was typed stays
            ARTIFACTS_DIR.mkdir(exist_ok=True)
            page.screenshot(path=str(ARTIFACTS_DIR / f"pool-form-hostile-count-{viewport[0]}.png"), full_page=True)
        finally:
            context.close()
