"""The demo LMS of `make run` (middleware/lti/demo_lms.py) as `telelab up` starts it: a child process on the port
after the lab's (or a free one), registered once, its course linked once to the demo course; it refuses what it
never sends (an unknown person, a launch back to another address) with a page, never a trace."""

from __future__ import annotations

import urllib.error
import urllib.request
from pathlib import Path
from urllib.parse import urlencode

from sqlalchemy import select

from tests.conftest import _let_go, make_test_app


def _get(url: str) -> tuple[int, str]:
    try:
        with urllib.request.urlopen(url, timeout=10) as response:
            return response.status, response.read().decode()
    except urllib.error.HTTPError as error:
        return error.code, error.read().decode()


def test_the_demo_lms_starts_beside_the_lab_registered_and_linked_to_the_demo_course_once(tmp_path: Path) -> None:
    from middleware.db import session_factory
    from middleware.demo_course import DEMO_COURSE_CODE
    from middleware.lab_runner import ensure_demo_accounts, seed_demo_course, start_demo_lms
    from middleware.lti import demo_lms
    from middleware.lti.demo_setup import seed_demo_lms
    from middleware.models import Course
    from middleware.models.lti import LtiContext, LtiPlatform

    app = make_test_app(f"sqlite:///{tmp_path / 'lab.sqlite3'}", "", tmp_path)
    try:
        ensure_demo_accounts(app)
        seed_demo_course(app)
        lms, seeded = start_demo_lms(app, "127.0.0.1", 5999)  # no lab on 5999: the tool's address is only named
        assert lms is not None
        try:
            assert len(seeded) == 2 and lms.url.startswith("http://127.0.0.1:")
            assert seed_demo_lms(app, lms.url, DEMO_COURSE_CODE) == []  # a second start adds nothing
            with session_factory(app)() as session:
                platform = session.scalars(select(LtiPlatform)).one()
                assert (platform.issuer, platform.client_id) == (lms.url, demo_lms.CLIENT_ID)
                linked = session.scalars(select(LtiContext)).one()
                assert session.get(Course, linked.course_id).code == DEMO_COURSE_CODE
            status, page = _get(lms.url + "/")
            assert status == 200 and "not a real LMS" in page and "Open Telelab as Lea (learner)" in page
            status, page = _get(lms.url + "/launch?person=admin")
            assert status == 400 and "not one the demo LMS makes" in page and "Traceback" not in page
            status, page = _get(lms.url + "/auth?" + urlencode({
                "login_hint": "learner", "redirect_uri": "https://elsewhere.example/steal", "client_id":
                demo_lms.CLIENT_ID, "nonce": "n", "state": "s"}))
            assert status == 400 and "id_token" not in page  # no signed launch for another address
            assert Path(app.instance_path, "demo-lms.json").exists()  # its key and grades outlive a restart
        finally:
            lms.stop()
    finally:
        _let_go(app)
        from middleware.lti.setup import _SENDER_KEY

        app.extensions[_SENDER_KEY].stop()


def test_the_demo_lms_takes_a_free_port_when_the_next_one_is_taken(tmp_path: Path) -> None:
    import socket
    from types import SimpleNamespace

    from middleware.lti.demo_setup import start_demo_lms

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        lms = start_demo_lms(SimpleNamespace(instance_path=str(tmp_path)), "http://127.0.0.1:5000", port)
        try:
            assert lms.url.startswith("http://127.0.0.1:") and not lms.url.endswith(f":{port}")
            assert _get(lms.url + "/gradebook")[0] == 200
        finally:
            lms.stop()
