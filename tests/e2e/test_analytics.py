"""The demo tutor reads the demo course's usage in Chromium, at desktop and phone size, from the state `telelab up`
seeds: Courses -> Usage of the lab, the course chosen, then what a person reads (the summary, time per student, the
heat map, queue waits, lab-1's uptime, the sessions) against the figures the API gives for the same query; the CSV
and the xAPI download answer. Screenshots in test-artifacts/."""

from __future__ import annotations

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_demo_journeys import SIZES, open_header_link

pytestmark = pytest.mark.e2e


@pytest.mark.parametrize("size", list(SIZES))
def test_the_demo_tutor_reads_the_demo_courses_usage(chromium, app, demo_accounts, live_server: LiveServer,
                                                     size: str) -> None:
    from middleware.analytics.demo import seed_demo_usage
    from middleware.demo_course import DEMO_COURSE_CODE
    from middleware.lab_runner import seed_demo_course

    seed_demo_course(app)
    assert seed_demo_usage(app), "the demo usage is seeded on a fresh lab"
    assert seed_demo_usage(app) == [], "and only once"
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    phone = size == "phone"
    context = chromium.new_context(viewport=SIZES[size], is_mobile=phone, has_touch=phone)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        page.goto(f"{live_server.url}/login")
        page.get_by_label("Username").fill("tutor")
        page.get_by_label("Password").fill(demo_accounts["tutor"])
        page.get_by_role("button", name="Log in").click()
        page.locator('[data-field="username"]').wait_for()
        open_header_link(page, "Courses")
        page.get_by_test_id("usage-link").click()
        page.locator("#analytics[data-state=ready]").wait_for()
        course = page.get_by_label("Course")
        demo = course.locator("option", has_text=DEMO_COURSE_CODE).get_attribute("value")
        course.select_option(value=demo)
        course_id = course.input_value()
        page.locator(f'#analytics[data-state=ready][data-course="{course_id}"]').wait_for()
        offset = int(page.evaluate("-new Date().getTimezoneOffset()"))
        figures = page.request.get(f"{live_server.url}/api/analytics/usage?course_id={course_id}"
                                   f"&utc_offset_min={offset}").json()
        assert figures.get("sessions_total", 0) > 10, figures

        summary = page.get_by_test_id("summary").text_content() or ""
        assert f"{figures['sessions_total']} sessions" in summary, summary
        students = page.get_by_test_id("students-table").locator("tbody tr")
        assert students.count() == len(figures["students"]) == 4  # the demo student and three classmates
        assert students.first.locator("td").first.text_content() == figures["students"][0]["username"]
        used = page.get_by_test_id("heat-map").locator("td.is-used")
        assert used.count() == sum(1 for day in figures["heat_map"] for minutes in day if minutes > 0) > 0
        waits = page.get_by_test_id("waits-summary").text_content() or ""
        assert waits.startswith(f"{figures['waits']['count']} turns granted"), waits
        bins = page.get_by_test_id("waits-bins").locator("li")
        assert bins.count() == 8 and bins.first.text_content().startswith("no wait")
        lab = page.get_by_test_id("robots-table").locator('tr[data-robot="lab-1"] td')
        lab_1 = next(r for r in figures["robots"] if r["robot_name"] == "lab-1")
        assert lab.nth(3).text_content() == f"{lab_1['uptime_pct']:.1f} %" and lab_1["outages"] >= 1
        assert page.get_by_test_id("sessions-table").locator("tbody tr").count() == min(200, figures["sessions_total"])
        page.screenshot(path=str(ARTIFACTS_DIR / f"analytics-course-{size}.png"), full_page=True)
        page.get_by_test_id("summary").scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / f"analytics-top-{size}.png"))
        page.get_by_test_id("robots-table").scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / f"analytics-robots-{size}.png"))

        heat = page.get_by_test_id("heat-map")
        heat.scroll_into_view_if_needed()
        page.screenshot(path=str(ARTIFACTS_DIR / f"analytics-heat-map-{size}.png"))
        if phone:
            overflow = page.evaluate("document.documentElement.scrollWidth - document.documentElement.clientWidth")
            wide = page.evaluate("""[...document.querySelectorAll('#analytics *')].filter((e) =>
                e.getBoundingClientRect().right > document.documentElement.clientWidth + 1
                && !e.closest('.analytics__heat-wrap, .analytics__table-wrap')).slice(0, 5)
                .map((e) => `${e.tagName}.${e.className} ${Math.round(e.getBoundingClientRect().right)}`)""")
            assert overflow <= 1, f"the page scrolls sideways on a phone by {overflow} px: {wide}"

        csv_link = page.locator('[data-csv="students"]')
        answer = page.request.get(f"{live_server.url}{csv_link.get_attribute('href')}")
        assert answer.status == 200 and answer.text().splitlines()[0] == "username,sessions,seconds_on_robots"
        xapi = page.get_by_test_id("xapi-link")
        assert xapi.is_visible()
        statements = page.request.get(f"{live_server.url}{xapi.get_attribute('href')}").json()["statements"]
        assert {s["verb"]["display"]["en"] for s in statements} >= {"attended"}
    finally:
        context.close()
    assert not errors, errors


def test_an_admin_reads_everyones_usage_and_whether_statements_reach_an_lrs(chromium, app, demo_accounts,
                                                                            live_server: LiveServer) -> None:
    from middleware.analytics.demo import seed_demo_usage
    from middleware.lab_runner import seed_demo_course

    seed_demo_course(app)
    seed_demo_usage(app)
    context = chromium.new_context(viewport=SIZES["desktop"])
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        page.goto(f"{live_server.url}/login")
        page.get_by_label("Username").fill("admin")
        page.get_by_label("Password").fill(demo_accounts["admin"])
        page.get_by_role("button", name="Log in").click()
        page.locator('[data-field="username"]').wait_for()
        page.goto(f"{live_server.url}/analytics")
        page.locator('#analytics[data-state=ready][data-course=""]').wait_for()
        assert page.get_by_label("Course").locator("option").first.text_content() == "Every course"
        assert "28 sessions" in (page.get_by_test_id("summary").text_content() or "")
        status = page.get_by_test_id("lrs-status")
        assert status.is_visible() and "No Learning Record Store is configured" in (status.text_content() or "")
        assert not page.get_by_test_id("xapi-link").is_visible(), "statements are per course"
        page.screenshot(path=str(ARTIFACTS_DIR / "analytics-admin-desktop.png"))
    finally:
        context.close()
    assert not errors, errors
