"""Telelab framed by an LMS of another SITE, in Chromium with third-party cookies blocked, as a person meets it.

The LMS's course page is http://127.0.0.1:<port>; Telelab is https://localhost:<port> (another site: a site is the
scheme and registrable domain, and an IP address and a host name never share one), served over TLS by Debian's
nginx configured as deploy/nginx/telelab.conf says for HTTPS (a certificate made here; Chromium told to accept it),
so its cookies are SameSite=None; Secure as in production.

How third-party cookies are blocked: Chromium's own setting, the one a person turns on in Settings > Privacy >
Third-party cookies, "Block third-party cookies" (the profile preference `profile.cookie_controls_mode`: 0 allow,
1 block, 2 block in Incognito only). Playwright has no option for it (microsoft/playwright#28597: "There is no
such feature") and `--test-third-party-cookie-phaseout` did not block them for its users (same thread); so each
browser here starts from a profile whose Preferences file holds the setting (a persistent context). The control
runs the same launch with the setting at 0 (allowed): it completes inside the frame, so what the blocked run shows
is the browser's refusal and not something else of the cross-site set-up. (Playwright's ordinary contexts are
off-the-record profiles, where Chromium 156 already blocks them: the mode 2 default.)
"""

from __future__ import annotations

import datetime
import json
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import NameOID

from tests.conftest import ARTIFACTS_DIR, CHROMIUM_ARGS, CHROMIUM_BROWSER_PATH, LiveServer, served_lab
from tests.e2e.test_class_across_workers import _nginx
from tests.e2e.test_panels import wait_for
from tests.integration.lti.conftest import register
from tests.integration.lti.platform import LEARNER, LmsPlatform

pytestmark = pytest.mark.e2e

ALLOW, BLOCK = 0, 1  # profile.cookie_controls_mode


def _certificate(folder: Path) -> tuple[Path, Path]:
    """A self-signed certificate for localhost (certificate, key)."""
    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "localhost")])
    now = datetime.datetime.now(datetime.UTC)
    certificate = (x509.CertificateBuilder().subject_name(name).issuer_name(name).public_key(key.public_key())
                   .serial_number(x509.random_serial_number()).not_valid_before(now - datetime.timedelta(hours=1))
                   .not_valid_after(now + datetime.timedelta(days=1))
                   .add_extension(x509.SubjectAlternativeName([x509.DNSName("localhost")]), critical=False)
                   .sign(key, hashes.SHA256()))
    cert_path, key_path = folder / "localhost.pem", folder / "localhost.key"
    cert_path.write_bytes(certificate.public_bytes(serialization.Encoding.PEM))
    key_path.write_bytes(key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                           serialization.NoEncryption()))
    return cert_path, key_path


@dataclass
class CrossSite:
    """Telelab behind TLS at https://localhost:<port>, and a registered LMS at http://127.0.0.1:<port>."""

    server: LiveServer
    tool_url: str
    lms: LmsPlatform


@pytest.fixture
def cross_site(skill_server_address: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[CrossSite]:
    """The lab with lab-1 behind nginx over HTTPS (the app trusts that one proxy, as the README's HTTPS set-up
    says), and a test LMS on another site registered with it."""
    monkeypatch.setenv("TELELAB_TRUSTED_PROXIES", "1")
    (tmp_path / "nginx").mkdir()
    with served_lab(f"lab-1={skill_server_address}", tmp_path) as server, \
            _nginx([server.url], tmp_path / "nginx", tls=_certificate(tmp_path)) as tool_url:
        lms = LmsPlatform(tool_url=tool_url)
        try:
            register(server, lms)
            yield CrossSite(server, tool_url, lms)
        finally:
            lms.stop()


def _browser(chromium, profile: Path, third_party_cookies: int):
    """Chromium (another process of the suite's Playwright) on a profile whose third-party-cookie setting is the
    given mode, accepting the test's certificate; (the browser, its pages' JavaScript errors)."""
    (profile / "Default").mkdir(parents=True)
    (profile / "Default" / "Preferences").write_text(json.dumps({"profile": {
        "cookie_controls_mode": third_party_cookies}}))
    browser = chromium.browser_type.launch_persistent_context(
        str(profile), executable_path=CHROMIUM_BROWSER_PATH, args=CHROMIUM_ARGS, ignore_https_errors=True,
        viewport={"width": 1280, "height": 800})
    errors: list[str] = []  # every page's uncaught errors (the page fixture's rule), checked at the end
    browser.on("page", lambda page: page.on("pageerror", lambda error: errors.append(str(error))))
    return browser, errors


def _number(scope, field: str) -> float:
    text = scope.locator(f'#console [data-field="{field}"]').first.text_content() or ""
    return float(text) if text.strip() not in {"", "—"} else float("nan")


def _drives(page, scope, focus) -> None:
    """The person presses the up arrow on the console: the robot moves and its odometry follows."""
    scope.locator('[data-connection="drive"][data-phase="open"]').wait_for(timeout=30000)
    wait_for(lambda: not math.isnan(_number(scope, "x")), 20, "no odometry arrived")
    x_before, y_before = _number(scope, "x"), _number(scope, "y")
    focus.click()
    page.keyboard.down("ArrowUp")
    wait_for(lambda: _number(scope, "linear") > 0.05, 10, "the robot did not move")
    time.sleep(0.8)
    page.keyboard.up("ArrowUp")
    wait_for(lambda: math.hypot(_number(scope, "x") - x_before, _number(scope, "y") - y_before) > 0.05, 5,
          "odometry did not follow the drive")


def _placed(setup: CrossSite) -> dict[str, str]:
    from middleware.lti.launches import sign_target

    key = setup.server.app.config["SECRET_KEY"]
    return {"telelab_target": "console:lab-1", "telelab_sig": sign_target(key, "course-1", "console:lab-1")}


def test_with_third_party_cookies_allowed_the_launch_completes_inside_the_other_sites_frame(
        chromium, cross_site: CrossSite, tmp_path: Path) -> None:
    lms = cross_site.lms
    lms.pending["drive"] = {"sub": "ada-learner", "roles": [LEARNER], "custom": _placed(cross_site)}
    browser, errors = _browser(chromium, tmp_path / "profile", ALLOW)
    try:
        page = browser.new_page()
        page.goto(f"{lms.url}/course?login_hint=drive")
        frame = page.frame_locator("#tool")
        frame.locator('#console[data-robot="lab-1"]').wait_for(timeout=30000)
        assert page.frames[1].url.startswith(cross_site.tool_url + "/lab/")  # inside the frame, another site
        _drives(page, frame, frame.get_by_role("heading", name="Lab 1"))
        assert not errors
    finally:
        browser.close()


def test_with_third_party_cookies_blocked_the_launch_offers_a_new_window_where_it_completes(
        chromium, cross_site: CrossSite, tmp_path: Path) -> None:
    lms = cross_site.lms
    lms.pending["drive"] = {"sub": "bea-learner", "roles": [LEARNER], "custom": _placed(cross_site)}
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    browser, errors = _browser(chromium, tmp_path / "profile", BLOCK)
    try:
        page = browser.new_page()
        page.goto(f"{lms.url}/course?login_hint=drive")
        frame = page.frame_locator("#tool")
        offer = frame.get_by_role("link", name="Open in a new window")
        offer.wait_for(timeout=30000)
        assert "third-party cookies are blocked" in frame.locator("#cookies-blocked").text_content()
        assert frame.locator("#console").count() == 0  # nothing launched inside the frame
        page.screenshot(path=str(ARTIFACTS_DIR / "lti-cross-site-cookies-blocked.png"))

        with browser.expect_page() as opened:
            offer.click()
        window = opened.value
        window.locator('#console[data-robot="lab-1"]').wait_for(timeout=30000)
        assert window.url.startswith(cross_site.tool_url + "/lab/")  # a top-level page of Telelab's own site
        _drives(window, window, window.get_by_role("heading", name="Lab 1"))
        window.screenshot(path=str(ARTIFACTS_DIR / "lti-cross-site-new-window-console.png"))
        assert not errors
    finally:
        browser.close()
