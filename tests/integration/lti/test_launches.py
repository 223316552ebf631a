"""LTI 1.3 launches from a test LMS (its own keys, served key set, signed id tokens): learners and instructors are
matched by issuer + subject and enrolled in the LMS course's Telelab course; hostile launches are refused with a
clear page and nothing is created."""

from __future__ import annotations

import html
import json
import re
import time
from pathlib import Path

import pytest
from sqlalchemy import func, select

from tests.conftest import LabClient, LiveServer, _let_go, make_test_app
from tests.integration.lti.conftest import begin_login, launch, register
from tests.integration.lti.platform import CLAIM, INSTRUCTOR, LEARNER, LMS_ADMIN, LmsPlatform


def _people(tool: LiveServer) -> dict[str, tuple[str, list[tuple[str, str]]]]:
    """username -> (role, [(course code, membership role)]) of every account an LMS made."""
    from middleware.db import session_factory
    from middleware.models import Course, CourseMembership, User
    from middleware.models.lti import LtiIdentity

    with session_factory(tool.app)() as session:
        out = {}
        for user, subject in session.execute(select(User, LtiIdentity.subject)
                                             .join(LtiIdentity, LtiIdentity.user_id == User.id)):
            courses = session.execute(select(Course.code, CourseMembership.role)
                                      .join(CourseMembership, CourseMembership.course_id == Course.id)
                                      .where(CourseMembership.user_id == user.id).order_by(Course.code)).all()
            out[subject] = (user.role, [tuple(c) for c in courses])
        return out


def _message(page: str) -> str:
    """The sentence the error page shows."""
    found = re.search(r'id="error-message">([^<]*)<', page)
    return html.unescape(found.group(1)) if found else page


def _counts(tool: LiveServer) -> dict[str, int]:
    from middleware.db import session_factory
    from middleware.models import Course, CourseMembership, User
    from middleware.models.lti import LtiContext, LtiIdentity

    with session_factory(tool.app)() as session:
        return {model.__name__: session.scalar(select(func.count()).select_from(model)) or 0
                for model in (User, Course, CourseMembership, LtiIdentity, LtiContext)}


def test_learner_and_instructor_launch_sign_in_matched_by_issuer_and_subject(tool: LiveServer,
                                                                            lms: LmsPlatform) -> None:
    teacher = LabClient(tool.url)
    status, headers, _ = launch(teacher, lms, "ana-instructor", [INSTRUCTOR])
    assert status == 303 and headers["Location"].endswith("/lab")
    status, _, body = teacher.request("GET", "/courses")
    assert status == 200 and "ROB101" in body  # the LMS course is a Telelab course the instructor teaches

    learner = LabClient(tool.url)
    assert launch(learner, lms, "bo-learner", [LEARNER], locale="es-ES")[0] == 303
    assert learner.request("GET", "/courses")[0] == 403  # a student, not a tutor
    admin = LabClient(tool.url)
    assert launch(admin, lms, "cy-lmsadmin", [LMS_ADMIN, LEARNER])[0] == 303
    assert admin.request("GET", "/admin/users")[0] == 403  # an LMS administrator is no lab admin

    people = _people(tool)
    assert people["ana-instructor"] == ("tutor", [("ROB101", "tutor")])
    assert people["bo-learner"] == ("student", [("ROB101", "student")])
    assert people["cy-lmsadmin"] == ("student", [("ROB101", "student")])

    again = LabClient(tool.url)  # the same person from another browser: the same account, nothing new
    before = _counts(tool)
    assert launch(again, lms, "bo-learner", [LEARNER], given_name="Someone else")[0] == 303
    assert _counts(tool) == before
    status, _, body = again.request("GET", "/lab")
    assert status == 200 and 'data-field="username">bo-' in body

    # The launch's locale claim (es-ES) is kept for the language choice (middleware/i18n.py).
    cookie = next(c for c in learner.cookies if c.name == "session")
    serializer = tool.app.session_interface.get_signing_serializer(tool.app)  # type: ignore[attr-defined]
    assert serializer.loads(cookie.value)["launch_locale"] == "es"


def test_a_person_of_another_lms_with_the_same_subject_is_another_account(tool: LiveServer,
                                                                         lms: LmsPlatform) -> None:
    other = LmsPlatform(tool_url=tool.url, client_id="other-client")
    register(tool, other)
    try:
        assert launch(LabClient(tool.url), lms, "same-subject", [LEARNER])[0] == 303
        assert launch(LabClient(tool.url), other, "same-subject", [LEARNER], context="course-9")[0] == 303
        from middleware.db import session_factory
        from middleware.models.lti import LtiIdentity

        with session_factory(tool.app)() as session:
            rows = session.execute(select(LtiIdentity.issuer, LtiIdentity.user_id)
                                   .where(LtiIdentity.subject == "same-subject")).all()
        assert len({user for _, user in rows}) == 2 and {iss for iss, _ in rows} == {lms.issuer, other.issuer}
    finally:
        other.stop()


def _forged_by(tool: LiveServer) -> LmsPlatform:
    forger = LmsPlatform(tool_url=tool.url, client_id="forger")
    register(tool, forger)
    return forger


HOSTILE = [
    # (case, how the launch is changed, code on the page, status)
    ("bad signature", {"signer": "stranger"}, "cannot be trusted", 401),
    ("wrong audience", {"change": {"aud": "someone-else"}}, "meant for another tool", 400),
    ("wrong audience in a list", {"change": {"aud": ["telelab-client", "x"], "azp": "x"}}, "meant for another tool",
     400),
    ("expired token", {"change": {"exp": int(time.time()) - 60, "iat": int(time.time()) - 400}}, "expired", 401),
    ("unknown deployment", {"change": {CLAIM + "deployment_id": "dep-999"}}, "deployment", 400),
    ("missing subject", {"drop": ("sub",)}, "claim", 400),
    ("missing roles", {"drop": (CLAIM + "roles",)}, "roles", 400),
    ("missing version", {"drop": (CLAIM + "version",)}, "LTI 1.3.0", 400),
    ("unknown issuer", {"change": {"iss": "https://unknown.example"}}, "not registered", 400),
    ("a subject reused by another issuer", {"signer": "forger"}, "cannot be trusted", 401),
]


@pytest.mark.parametrize(("case", "how", "says", "status"), HOSTILE, ids=[row[0] for row in HOSTILE])
def test_hostile_launch_is_refused_with_a_clear_page_and_creates_nothing(tool: LiveServer, lms: LmsPlatform,
                                                                        case: str, how: dict, says: str,
                                                                        status: int) -> None:
    assert launch(LabClient(tool.url), lms, "victim-learner", [LEARNER])[0] == 303  # the subject exists under lms
    before = _counts(tool)
    signer = None
    forger = None
    if how.get("signer") == "stranger":
        signer = LmsPlatform(tool_url=tool.url)
        signer.public_jwk["kid"] = lms.public_jwk["kid"]  # claims the LMS's key id, signed with another key
        signer.stop()
    elif how.get("signer") == "forger":
        forger = signer = _forged_by(tool)  # a registered LMS signing as the first one, for its subject
    client = LabClient(tool.url)
    try:
        got, _, body = launch(client, lms, "victim-learner" if forger else "mallory", [LEARNER], signer=signer,
                              change=how.get("change"), drop=how.get("drop", ()))
    finally:
        if forger:
            forger.stop()
    message = _message(body)
    assert got == status, message
    assert says in message
    assert _counts(tool) == before
    assert client.request("GET", "/lab")[0] == 302  # not signed in


def test_a_replayed_launch_is_refused(tool: LiveServer, lms: LmsPlatform) -> None:
    client = LabClient(tool.url)
    nonce, state = begin_login(client, lms)
    token = lms.sign(lms.claims(nonce, "replay-learner", [LEARNER]))
    assert client.request("POST", "/lti/launch", {"id_token": token, "state": state})[0] == 303
    before = _counts(tool)
    thief = LabClient(tool.url)
    thief.cookies = client.cookies  # even with the victim's state cookie
    status, _, body = thief.request("POST", "/lti/launch", {"id_token": token, "state": state})
    assert status == 401 and "already used" in _message(body)
    assert _counts(tool) == before


def test_a_launch_without_its_state_cookie_says_to_open_a_new_window(tool: LiveServer, lms: LmsPlatform) -> None:
    nonce, state = begin_login(LabClient(tool.url), lms)
    status, _, body = LabClient(tool.url).request("POST", "/lti/launch", {
        "id_token": lms.sign(lms.claims(nonce, "x-learner", [LEARNER])), "state": state})
    assert status == 400 and "new window" in _message(body)


def test_a_refused_launch_speaks_the_browsers_spanish(tool: LiveServer, lms: LmsPlatform) -> None:
    client = LabClient(tool.url)
    nonce, state = begin_login(client, lms)
    claims = lms.claims(nonce, "es-learner", [LEARNER])
    claims["exp"] = claims["iat"] - 10
    before = _counts(tool)
    status, _, body = client.request("POST", "/lti/launch", {"id_token": lms.sign(claims), "state": state},
                                     headers={"Accept-Language": "es-ES,es;q=0.9"})
    assert status == 401 and _message(body) == "El lanzamiento ha caducado. Vuelve a empezarlo desde el LMS."
    assert 'lang="es"' in body and _counts(tool) == before
    nonce, state = begin_login(client, lms)  # a library message with a value: the claim it lacks, in place
    claims = lms.claims(nonce, "es-learner", [LEARNER])
    claims.pop("sub")
    status, _, body = client.request("POST", "/lti/launch", {"id_token": lms.sign(claims), "state": state},
                                     headers={"Accept-Language": "es"})
    assert status == 400 and _message(body).startswith("Al lanzamiento le falta un claim obligatorio (sub")


def test_the_login_first_checks_cookies_and_offers_a_new_window(tool: LiveServer, lms: LmsPlatform) -> None:
    status, _, body = LabClient(tool.url).request("POST", "/lti/login", {
        "iss": lms.issuer, "login_hint": "h", "client_id": lms.client_id})
    assert status == 200 and "Open in a new window" in body and "lti1p3_new_window=1" in body


def test_pages_may_be_framed_only_by_registered_platforms(tool: LiveServer, lms: LmsPlatform) -> None:
    _, headers, _ = LabClient(tool.url).request("GET", "/login")
    policy = headers["Content-Security-Policy"]
    framers = policy.split("frame-ancestors ")[1].split(";")[0].split()
    assert lms.issuer in framers and "'none'" not in framers
    assert "X-Frame-Options" not in headers


def test_the_jwks_serves_every_unretired_key_and_rotation_keeps_the_old_one(tool: LiveServer) -> None:
    from middleware.db import unit_of_work
    from middleware.lti import keys

    first = LabClient(tool.url).request("GET", "/lti/jwks.json")
    kids = [k["kid"] for k in json.loads(first[2])["keys"]]
    with tool.app.app_context(), unit_of_work(tool.app) as session:
        new = keys.rotate(session).kid
    after = [k["kid"] for k in json.loads(LabClient(tool.url).request("GET", "/lti/jwks.json")[2])["keys"]]
    assert after[0] == new and set(kids) <= set(after)
    with tool.app.app_context(), unit_of_work(tool.app) as session:
        keys.retire(session, kids[0])
    final = [k["kid"] for k in json.loads(LabClient(tool.url).request("GET", "/lti/jwks.json")[2])["keys"]]
    assert kids[0] not in final and new in final


def test_the_session_cookie_crosses_sites_over_https_only_once_a_platform_is_registered(tool: LiveServer,
                                                                                        lms: LmsPlatform,
                                                                                        tmp_path: Path) -> None:
    app = tool.app
    with app.test_request_context("/", base_url="https://telelab.example.edu"):
        assert app.session_interface.get_cookie_samesite(app) == "None"
        assert app.session_interface.get_cookie_secure(app)
    with app.test_request_context("/", base_url="http://127.0.0.1"):
        assert app.session_interface.get_cookie_samesite(app) == app.config["SESSION_COOKIE_SAMESITE"]
    bare = make_test_app(f"sqlite:///{tmp_path / 'bare.sqlite3'}", "", tmp_path)  # no platform: not embedded
    try:
        with bare.test_request_context("/", base_url="https://telelab.example.edu"):
            assert bare.session_interface.get_cookie_samesite(bare) == bare.config["SESSION_COOKIE_SAMESITE"]
        with bare.test_client() as client:
            headers = client.get("/healthz").headers
        assert headers["X-Frame-Options"] == "DENY"
        assert "frame-ancestors 'none'" in headers["Content-Security-Policy"]
    finally:
        _let_go(bare)

