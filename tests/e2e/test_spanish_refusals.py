"""What the lab refuses, as a Spanish student reads it in Chromium set to Spanish (es-ES) at desktop and phone sizes:
the bookings page of a course that allows no bookings says why in Spanish, an invitation link that cannot be used and
an address with nothing at it say so in Spanish, and a refused chat message is answered in Spanish; no English word
is left where a person reads, nothing scrolls sideways; screenshots in test-artifacts/spanish-*.png."""

from __future__ import annotations

import re

import pytest

from tests.conftest import LiveServer
from tests.e2e.test_spanish import english_left, log_in, look, spanish_tab

pytestmark = pytest.mark.e2e


@pytest.fixture
def course_without_bookings(app) -> None:
    """student1 in a course that allows no bookings."""
    from middleware.db import session_factory
    from middleware.models import Course, CourseMembership, User

    with session_factory(app)() as session:
        student = session.query(User).filter(User.username == "student1").one()
        course = Course(code="ROB-0", title="Sin reservas", booking_allowance_min=0)
        session.add(course)
        session.flush()
        session.add(CourseMembership(course_id=course.id, user_id=student.id, role="student"))
        session.commit()


def test_a_spanish_student_reads_what_is_refused_in_spanish(chromium, live_server: LiveServer,
                                                           course_without_bookings) -> None:
    context, tab, errors = spanish_tab(chromium)
    try:
        tab.goto(f"{live_server.url}/join/not-a-token")
        tab.get_by_role("heading", name="Este enlace de invitación no es válido").wait_for()
        look(tab, "refused-invitation")

        log_in(tab, live_server, "student1")
        tab.goto(f"{live_server.url}/bookings")
        tab.locator("#bookings").wait_for()
        if tab.locator(".slot--free, .slot--unavailable").count() == 0:  # late on a Sunday: this week is over
            tab.locator('a[rel="next"]').click()
        tab.locator("#unavailable-reasons", has_text="Tu curso no permite reservas").wait_for()
        shown = tab.locator('[data-unavailable="no allowance"] .slot__what').all_text_contents()
        assert shown and set(shown) == {"sin asignación"}, shown
        days = re.findall(r"\b(?:Mon|Tue|Wed|Thu|Fri|Sat|Sun) \d\d \w+", tab.evaluate("document.body.innerText"))
        assert not days, f"the week's days are written in English: {days[:3]}"
        look(tab, "refused-bookings")

        tab.goto(f"{live_server.url}/no-such-page")
        tab.get_by_role("heading", name="No encontrado").wait_for()
        tab.locator("#error-message", has_text="No hay nada en esta dirección.").wait_for()
        look(tab, "refused-address")

        answer = tab.evaluate("""async () => {
          const token = document.querySelector('meta[name="csrf-token"]')?.content || "";
          const response = await fetch("/api/robots/lab-1/chat", {method: "POST",
            headers: {"Content-Type": "application/json", "X-CSRFToken": token},
            body: JSON.stringify({body: "x".repeat(501)})});
          return [response.status, await response.json()];
        }""")
        assert answer[0] == 400, answer
        assert answer[1]["error"]["message"] == "Un mensaje puede tener como mucho 500 caracteres; este tiene 501."
        assert not english_left(tab)
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"
