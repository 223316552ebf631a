"""The LTI Advantage services against the test LMS: a tutor places a test by deep linking, a learner's final mark
and a tutor's override reach the recording AGS endpoint (after a failure shown to the tutor with its reason, and
a retry), and a tutor syncs the roster from NRPS."""

from __future__ import annotations

import html
import re
import time
from collections.abc import Callable
from typing import Any
from urllib.parse import urlencode
from urllib.request import Request, urlopen

from sqlalchemy import select

from tests.conftest import LabClient, LiveServer
from tests.integration.bookings.conftest import api
from tests.integration.lti.conftest import launch
from tests.integration.lti.platform import INSTRUCTOR, LEARNER, LmsPlatform


def wait_for(check: Callable[[], Any], timeout_s: float = 30.0) -> Any:
    """check()'s first truthy answer (the grade sender is a thread of the served app)."""
    deadline = time.monotonic() + timeout_s
    while True:
        answer = check()
        if answer or time.monotonic() > deadline:
            return answer
        time.sleep(0.1)


def _inputs(page: str) -> dict[str, str]:
    return {m.group(1): html.unescape(m.group(2))
            for m in re.finditer(r'<input type="hidden" name="([^"]+)" value="([^"]*)"', page)}


def _course_id(tool: LiveServer) -> int:
    from middleware.db import session_factory
    from middleware.models.lti import LtiContext

    with session_factory(tool.app)() as session:
        return int(session.scalar(select(LtiContext.course_id).where(LtiContext.context_id == "course-1")))


def test_a_placed_test_sends_final_and_overridden_marks_to_the_gradebook(tool: LiveServer, lms: LmsPlatform) -> None:
    tutor = LabClient(tool.url)
    assert launch(tutor, lms, "tina-instructor", [INSTRUCTOR])[0] == 303
    course = _course_id(tool)
    status, question = api(tutor, "POST", f"/api/courses/{course}/questions",
                           {"kind": "text", "prompt": "Which sensor measures range?", "accepted": ["sonar"],
                            "points": 2})
    assert status == 201, question
    qid = question["question"]["id"] if "question" in question else question["id"]
    status, exam = api(tutor, "POST", f"/api/courses/{course}/exams",
                       {"title": "Sensors quiz", "kind": "quiz", "question_ids": [qid]})
    assert status == 201, exam
    exam_id = exam["exam"]["id"] if "exam" in exam else exam["id"]

    # Deep linking: the instructor places the test; the LMS checks the answer's signature with the tool's JWKS.
    status, _, picker = launch(tutor, lms, "tina-instructor", [INSTRUCTOR], deep_link=True)
    assert status == 200 and "Sensors quiz" in picker and "Class session" in picker
    form = _inputs(picker)
    status, _, answer = tutor.request("POST", "/lti/deep-link", {
        "csrf_token": form["csrf_token"], "launch_id": form["launch_id"], "target": f"exam:{exam_id}"})
    assert status == 200, answer
    action = html.unescape(re.search(r'action="([^"]+)"', answer[answer.index('id="deep-link-return"') - 200:])
                           .group(1))
    assert action == lms.url + "/deep-link-return"
    with urlopen(Request(action, data=urlencode({"JWT": _inputs(answer)["JWT"]}).encode()), timeout=10) as reply:
        assert reply.status == 200
    item = lms.deep_link_returns[-1]["https://purl.imsglobal.org/spec/lti-dl/claim/content_items"][0]
    assert item["title"] == "Sensors quiz" and item["lineItem"]["scoreMaximum"] == 100
    assert item["custom"]["telelab_target"] == f"exam:{exam_id}" and item["url"] == tool.url + "/lti/launch"

    # The learner opens the placed test (the LMS sends its custom parameters and line item back).
    learner = LabClient(tool.url)
    lms.fail_scores = 1
    status, headers, _ = launch(learner, lms, "lu-learner", [LEARNER], custom=item["custom"],
                                lineitem=lms.url + "/lineitems/7")
    assert status == 303 and headers["Location"].endswith(f"/assessment/exams/{exam_id}")
    status, started = api(learner, "POST", f"/api/exams/{exam_id}/attempts")
    assert status == 201, started
    attempt_id = started["attempt"]["id"]
    status, submitted = api(learner, "POST", f"/api/attempts/{attempt_id}/submit", {"answers": {str(qid): "sonar"}})
    assert status == 200 and submitted["attempt"]["score"] == 2

    # The LMS answers 503 once: the tutor reads why the grade waits, then "Retry now" sends it.
    page = wait_for(lambda: (p := tutor.request("GET", f"/courses/{course}")[2]) and "maintenance" in p and p)
    assert page and "The LMS answered 503" in page and re.search(r"lu-[0-9a-f]{6}", page)
    spanish = tutor.request("GET", f"/courses/{course}", headers={"Accept-Language": "es"})[2]
    assert "El LMS respondió 503 SERVICE UNAVAILABLE: gradebook is down for maintenance (intentos: 1)" in spanish
    status, _, _ = tutor.request("POST", f"/courses/{course}/lti/grades/retry",
                                 {"csrf_token": tutor.csrf_token(f"/courses/{course}")})
    assert status == 303
    assert wait_for(lambda: len(lms.scores) == 1), "the grade never reached the LMS"
    score = lms.scores[0]
    assert score["lineitem"] == "/lineitems/7" and score["userId"] == "lu-learner"
    assert (score["scoreGiven"], score["scoreMaximum"], score["gradingProgress"]) == (2, 2, "FullyGraded")

    # A tutor's override sends the new mark.
    status, _ = api(tutor, "POST", f"/api/attempts/{attempt_id}/overrides",
                    {"item": str(qid), "points": 1.5, "reason": "Half the justification"})
    assert status in (200, 201)
    assert wait_for(lambda: len(lms.scores) == 2), "the override never reached the LMS"
    assert lms.scores[1]["scoreGiven"] == 1.5
    page = tutor.request("GET", f"/courses/{course}")[2]
    assert 'id="grades-sent">2 sent.' in page and "grades-waiting" not in page


def test_a_failed_grade_survives_a_restart_and_another_worker_sends_it(tool: LiveServer, lms: LmsPlatform) -> None:
    """The outbox is in the database: rows a process left pending are sent by whichever process claims them."""
    from middleware.db import session_factory
    from middleware.lti import grades
    from middleware.models.accounts import utc_now
    from middleware.models.lti import LtiGradePassback

    with session_factory(tool.app)() as session:
        row = session.scalars(select(LtiGradePassback).order_by(LtiGradePassback.id.desc())).first()
        assert row is not None
        session.add(LtiGradePassback(attempt_id=row.attempt_id, line_item_id=row.line_item_id, user_id=row.user_id,
                                     score_given=1.0, score_maximum=2.0, status="pending", next_try_at=utc_now(),
                                     claimed_by="a-dead-worker", claimed_until=utc_now()))  # its claim lapsed
        session.commit()
    before = len(lms.scores)
    sent, failed = grades.send_due(session_factory(tool.app))
    assert (sent, failed) == (1, 0) or wait_for(lambda: len(lms.scores) == before + 1)
    assert grades.send_due(session_factory(tool.app)) == (0, 0)  # nothing is sent twice


def test_a_tutor_syncs_the_roster_from_the_lms(tool: LiveServer, lms: LmsPlatform) -> None:
    tutor = LabClient(tool.url)
    assert launch(tutor, lms, "tina-instructor", [INSTRUCTOR])[0] == 303
    assert launch(LabClient(tool.url), lms, "gone-learner", [LEARNER])[0] == 303
    course = _course_id(tool)
    lms.members = [
        {"user_id": "tina-instructor", "roles": [INSTRUCTOR], "status": "Active", "name": "Tina"},
        {"user_id": "new-learner", "roles": [LEARNER], "status": "Active", "name": "Nadia New", "given_name": "Nadia"},
        {"user_id": "gone-learner", "roles": [LEARNER], "status": "Inactive"},
    ]
    status, headers, _ = tutor.request("POST", f"/courses/{course}/lti/roster",
                                       {"csrf_token": tutor.csrf_token(f"/courses/{course}")})
    assert status == 303
    page = tutor.request("GET", f"/courses/{course}")[2]
    flash = re.search(r'class="flash[^"]*">([^<]*)<', page)
    assert flash and "Roster synced from the LMS: 1 enrolled" in flash.group(1) and "removed" in flash.group(1), \
        flash and flash.group(1)
    assert re.search(r"nadia-[0-9a-f]{6}", page) and not re.search(r">gone-[0-9a-f]{6}<", page)
    learner = LabClient(tool.url)  # a student may not sync
    assert launch(learner, lms, "new-learner", [LEARNER])[0] == 303
    assert learner.request("POST", f"/courses/{course}/lti/roster",
                           {"csrf_token": learner.csrf_token("/account/password")})[0] == 403


def test_only_the_instructor_who_asked_answers_a_deep_link(tool: LiveServer, lms: LmsPlatform) -> None:
    tutor = LabClient(tool.url)
    status, _, picker = launch(tutor, lms, "tina-instructor", [INSTRUCTOR], deep_link=True)
    launch_id = _inputs(picker)["launch_id"]
    other = LabClient(tool.url)
    assert launch(other, lms, "otto-instructor", [INSTRUCTOR])[0] == 303
    status, _, page = other.request("POST", "/lti/deep-link", {
        "csrf_token": other.csrf_token("/account/password"), "launch_id": launch_id, "target": "class:"})
    assert status == 403 and "someone else" in page
    learner = LabClient(tool.url)
    status, _, page = launch(learner, lms, "lu-learner", [LEARNER], deep_link=True)
    assert status == 403 and "instructors" in page
    # A link whose target Telelab did not sign (custom parameters typed into the LMS) opens nothing.
    status, _, page = launch(LabClient(tool.url), lms, "lu-learner", [LEARNER],
                             custom={"telelab_target": "exam:1", "telelab_sig": "0" * 32})
    assert status == 400 and "not placed by Telelab" in html.unescape(page)
