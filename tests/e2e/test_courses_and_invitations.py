"""A tutor creates a course, uploads a CSV and reads the report; an invited student joins and lands in the lab."""

from __future__ import annotations

import re

import pytest

from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer
from tests.integration.bookings.conftest import course_people  # noqa: F401

pytestmark = pytest.mark.e2e


def log_in(tab, live_server: LiveServer, username: str) -> None:
    tab.goto(f"{live_server.url}/login")
    tab.fill("#username", username)
    tab.fill("#password", STUDENT_PASSWORD)
    tab.get_by_role("button", name="Log in").click()
    tab.locator('[data-field="username"]').wait_for()


def test_tutor_enrols_a_class_from_csv_and_an_invited_student_joins(chromium, page, live_server: LiveServer,
                                                                     course_people, tmp_path) -> None:  # noqa: F811
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    log_in(page, live_server, "tutor1")
    page.get_by_role("link", name="Courses").click()
    page.get_by_label("Code").fill("NAV-1")
    page.get_by_label("Title").fill("Navigation")
    page.get_by_label("Turn length (seconds)").fill("5")
    page.get_by_role("button", name="Create course").click()
    error = page.locator('[data-error-for="turn_length_s"]')
    assert "from 10 to 3600" in error.text_content()
    assert page.get_by_label("Turn length (seconds)").get_attribute("aria-invalid") == "true"
    page.screenshot(path=str(ARTIFACTS_DIR / "courses-field-error-desktop.png"), full_page=True)
    page.get_by_label("Turn length (seconds)").fill("90")
    page.get_by_role("button", name="Create course").click()
    page.locator("h1", has_text="NAV-1 · Navigation").wait_for()

    roster = tmp_path / "class.csv"
    roster.write_text("\ufeffusername\nstudent1\nnewstudent\ntutor2\nstudent1\n=1+1\n", encoding="utf-8")
    page.get_by_label("CSV file of usernames").set_input_files(str(roster))
    page.get_by_role("button", name="Upload and enrol").click()
    report = page.locator("#csv-report")
    report.wait_for()
    assert report.locator('[data-field="created-count"]').text_content() == "1"
    assert report.locator('[data-field="refused-count"]').text_content() == "3"
    assert "tutor account" in report.locator("#refused-rows").text_content()
    with page.expect_download() as download:
        page.get_by_role("link", name="Download the report (CSV)").click()
    saved = tmp_path / "report.csv"
    download.value.save_as(saved)
    assert "newstudent" in saved.read_text() and "'=1+1" in saved.read_text()
    page.screenshot(path=str(ARTIFACTS_DIR / "courses-report-desktop.png"), full_page=True)
    course_url = page.url.removesuffix("/members.csv")  # the upload answered on the form's URL

    page.get_by_role("button", name="Create an invitation link").click()
    link = page.locator("#invitation-link").text_content().strip()
    assert "/join/" in link
    page.context.grant_permissions(["clipboard-read", "clipboard-write"], origin=live_server.url)
    page.get_by_role("button", name="Copy the link").click()
    page.get_by_role("status").filter(has_text="Link copied.").wait_for()
    assert page.evaluate("navigator.clipboard.readText()") == link
    page.screenshot(path=str(ARTIFACTS_DIR / "invitation-copied-desktop.png"))

    phone_context = chromium.new_context(viewport={"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    phone = phone_context.new_page()
    errors: list[str] = []
    phone.on("pageerror", lambda e: errors.append(str(e)))
    try:
        phone.goto(link)
        phone.get_by_label("Username").fill("invitee")
        phone.get_by_label("Password", exact=True).fill("my-own-long-password")
        phone.get_by_label("Password again").fill("my-own-long-password")
        phone.screenshot(path=str(ARTIFACTS_DIR / "join-phone.png"), full_page=True)
        phone.get_by_role("button", name="Create my account").click()
        phone.locator(".robot-list, .empty-state").first.wait_for()
        assert phone.url.endswith("/lab")
        assert phone.locator('[data-field="username"]').text_content() == "invitee"
        phone.goto(link)
        assert "already been used" in phone.locator("#error-heading").text_content()
        assert errors == []
    finally:
        phone_context.close()

    # A second link, withdrawn from the course page before anyone uses it.
    page.goto(course_url)
    page.get_by_role("button", name="Create an invitation link").click()
    withdrawn = page.locator("#invitation-link").text_content().strip()
    page.goto(course_url)
    page.locator("#course-invitations button", has_text="Withdraw").first.click()
    page.locator(".flash, [role=status], [role=alert]", has_text="withdrawn").first.wait_for()
    listed = page.locator("#course-invitations").text_content()
    assert "revoked" in listed
    # Dates read as words, not as ISO: "expires Wed 02 Dec 2026, 15:10 UTC".
    assert re.search(r"expires [A-Z][a-z]{2} \d{2} [A-Z][a-z]{2} \d{4}, \d{2}:\d{2} UTC", listed), listed
    page.screenshot(path=str(ARTIFACTS_DIR / "courses-invitation-withdrawn.png"), full_page=True)
    page.goto(withdrawn)
    assert "withdrawn" in page.locator("#error-heading").text_content()

    page.goto(f"{live_server.url}/courses")
    page.set_viewport_size({"width": 390, "height": 844})
    page.screenshot(path=str(ARTIFACTS_DIR / "courses-phone.png"), full_page=True)
