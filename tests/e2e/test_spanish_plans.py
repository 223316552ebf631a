"""A Spanish student's plan editor in Chromium set to Spanish (es-ES): a plan with two errors is checked and each
error reads in Spanish on its own line of the list, its line marked, and saving it says the first error and how many
more in Spanish; at desktop and phone sizes, nothing wider than the screen (test-artifacts/spanish-plan-errors-*.png).
The plan's keywords and skill names stay as they are written."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_spanish import DESKTOP, ENGLISH, PHONE, log_in, spanish_tab

pytestmark = pytest.mark.e2e

TWO_ERRORS = 'say "hola"\ngo_to 120 0\nset max_sped 0.3\n'
RANGE = "línea 2, columna 7: goal_x_m debe estar entre -50 y 50 m; se recibió 120."
SETTING = ("línea 3, columna 5: 'max_sped' no es un ajuste (¿querías decir max_speed?); usa max_speed, "
           "max_turn_rate, watchdog.")
# A plan made as the list page makes one (its creation in English is tests/e2e/test_plans.py's journey).
CREATE = """async (name) => {
    const token = document.querySelector('meta[name=csrf-token]').content;
    const answer = await fetch('/api/plans', {method: 'POST', body: JSON.stringify({name, text: 'say "hola"\\n'}),
      headers: {'Content-Type': 'application/json', 'X-CSRFToken': token, 'Accept': 'application/json'}});
    return (await answer.json()).plan.id;
}"""


def at_each_size(tab, shown) -> dict[str, list]:
    """The page's language and how far it scrolls sideways on a desktop and on a phone, with a screenshot of shown
    at each (test-artifacts/spanish-plan-errors-<size>.png)."""
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    seen = {}
    for size, viewport in (("desktop", DESKTOP), ("phone", PHONE)):
        tab.set_viewport_size(viewport)
        shown.scroll_into_view_if_needed()
        tab.wait_for_timeout(150)  # the menu folds on a phone (on its media query's change)
        seen[size] = tab.evaluate("[document.documentElement.lang, "
                                  "document.documentElement.scrollWidth - window.innerWidth]")
        tab.screenshot(path=str(ARTIFACTS_DIR / f"spanish-plan-errors-{size}.png"), full_page=True)
    return seen


def test_a_spanish_student_reads_a_plans_errors_in_spanish(chromium, live_server: LiveServer) -> None:
    context, tab, errors = spanish_tab(chromium)
    try:
        log_in(tab, live_server, "student1")
        tab.goto(f"{live_server.url}/plans")
        tab.goto(f"{live_server.url}/plans/{tab.evaluate(CREATE, 'dos-errores')}")
        editor = tab.get_by_label("El texto del plan, una orden por línea")
        editor.fill(TWO_ERRORS)
        tab.get_by_role("button", name="Comprobar", exact=True).click()
        tab.locator(".plan-code__line--error[data-line='3']").wait_for()
        assert tab.locator(".plan-code__line--error").count() == 2
        items = tab.locator("[data-slot=errors] li")
        said = [items.nth(i).inner_text() for i in range(items.count())]
        assert said == [f"Línea 2, columna 7 {RANGE}", f"Línea 3, columna 5 {SETTING}"], said
        assert not [line for line in said if ENGLISH.search(line)], said
        assert "2 problemas encontrados" in tab.locator("[data-field=check-status]").inner_text()

        tab.get_by_role("button", name="Guardar", exact=True).click()
        tab.locator("[data-field=check-status]", has_text="(y 1 problema más)").wait_for()
        assert tab.locator("[data-field=check-status]").inner_text() == f"{RANGE} (y 1 problema más)"
        assert tab.get_by_role("radio", name="donde está ahora lab-1").is_checked()  # one sentence, not two halves
        seen = at_each_size(tab, items.first)
        assert all(lang == "es" and sideways <= 1 for lang, sideways in seen.values()), \
            f"the plan's errors, (lang, px scrolled sideways) at each size: {seen}"
    finally:
        context.close()
    assert not errors, f"JavaScript errors: {errors}"
