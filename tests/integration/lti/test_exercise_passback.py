"""An exercise attached to a course as a test sends its marks to the LMS gradebook through the grade outbox: the
instructor places it by deep linking (a column out of the test's points), a learner's graded submission reaches the
test LMS's score endpoint for that learner, a failure waits with the LMS's reason on the tutor's course page until
"Retry now", a newer mark supersedes one still waiting, a change of the test's points sends the new mark, and a
student the LMS does not know queues nothing.

No robot runs here (tests/integration/exercises/ grade real runs): a submission is opened and finished through the
exercises' services in a request's unit of work, as the finish route does, with the robot's pose log read from a
trace the test gives. The grading, the mark, the outbox row, the commit, the grade sender and the LMS are real."""

from __future__ import annotations

import html
import re
from datetime import UTC, datetime, timedelta
from urllib.parse import urlencode, urlsplit
from urllib.request import Request, urlopen

from sqlalchemy import select

from tests.conftest import LabClient, LiveServer
from tests.integration.bookings.conftest import api
from tests.integration.lti.conftest import launch
from tests.integration.lti.platform import INSTRUCTOR, LEARNER, LmsPlatform
from tests.integration.lti.test_services import _course_id, _inputs, wait_for

# "Reach the goal around the pillar": graded by the closest approach to the goal (3.2, -1.5), 1 within 0.4 m, 0.5
# within 0.8 m.
SLUG = "obstacle-avoidance"
TITLE = "Reach the goal around the pillar"
CONTENT_ITEMS = "https://purl.imsglobal.org/spec/lti-dl/claim/content_items"


def _submit(tool: LiveServer, username: str, closest_m: float, slug: str = SLUG,
            started: datetime | None = None) -> float:
    """A graded submission of username's whose robot came within closest_m of the goal; its fraction."""
    from middleware.db import finish_request, get_session
    from middleware.exercises import services
    from middleware.models import User

    begun = started or datetime.now(UTC)
    goal_x, goal_y = 3.2, -1.5

    def pose_log(_robot: str, _since: datetime, _until: datetime) -> list[list[float]]:
        return [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [4.0, goal_x - closest_m, goal_y, 0.0, 0.0, 0.0, 0.0]]

    with tool.app.test_request_context():
        session = get_session()
        user = session.scalar(select(User).where(User.username == username))
        assert user is not None
        exercise = services.exercise_by_slug(session, slug)
        code = services.save_code(session, user, exercise, f"# {closest_m}\nrobot.stop()", begun)
        run = services.begin_run(session, user, exercise, code, "submission", "lab-1", exercise.scene,
                                 lambda _start: None, lambda: begun, pose_log)
        services.finish_run(session, user, run, None, pose_log, begun + timedelta(seconds=5))
        fraction = run.fraction
        finish_request()  # the request's commit, then what waits for it (the grade sender's wake-up)
    assert fraction is not None
    return fraction


def _username(tool: LiveServer, subject: str) -> str:
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.lti import LtiIdentity

    with session_factory(tool.app)() as session:
        return str(session.scalar(select(User.username).join(LtiIdentity, LtiIdentity.user_id == User.id)
                                  .where(LtiIdentity.subject == subject)))


def _passbacks(tool: LiveServer, username: str) -> list[tuple[float, float, str]]:
    """(score, maximum, status) of every outbox row of username's, oldest first."""
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.lti import LtiGradePassback

    with session_factory(tool.app)() as session:
        rows = session.execute(select(LtiGradePassback).join(User, User.id == LtiGradePassback.user_id)
                               .where(User.username == username).order_by(LtiGradePassback.id)).scalars()
        return [(row.score_given, row.score_maximum, row.status) for row in rows]


def _attach(tutor: LabClient, course: int, points: float, slug: str = SLUG, days: int = 7) -> None:
    deadline = (datetime.now(UTC) + timedelta(days=days)).isoformat()
    status, answer = api(tutor, "POST", f"/api/courses/{course}/exercises",
                         {"slug": slug, "deadline_at": deadline, "points": points})
    assert status in (200, 201), answer


def _place(tutor: LabClient, lms: LmsPlatform, target: str) -> dict:
    """The instructor places target by deep linking; the content item the LMS received."""
    status, _, picker = launch(tutor, lms, "tina-instructor", [INSTRUCTOR], deep_link=True)
    assert status == 200, picker
    form = _inputs(picker)
    status, _, answer = tutor.request("POST", "/lti/deep-link", {
        "csrf_token": form["csrf_token"], "launch_id": form["launch_id"], "target": target})
    assert status == 200, answer
    action = html.unescape(re.search(r'action="([^"]+)"', answer[answer.index('id="deep-link-return"') - 200:])
                           .group(1))
    with urlopen(Request(action, data=urlencode({"JWT": _inputs(answer)["JWT"]}).encode()), timeout=10) as reply:
        assert reply.status == 200
    return lms.deep_link_returns[-1][CONTENT_ITEMS][0]


def _retry(tutor: LabClient, course: int) -> None:
    status, _, _ = tutor.request("POST", f"/courses/{course}/lti/grades/retry",
                                 {"csrf_token": tutor.csrf_token(f"/courses/{course}")})
    assert status == 303


def test_a_placed_exercise_test_sends_the_learners_marks_to_the_gradebook(tool: LiveServer,
                                                                           lms: LmsPlatform) -> None:
    tutor = LabClient(tool.url)
    assert launch(tutor, lms, "tina-instructor", [INSTRUCTOR])[0] == 303
    course = _course_id(tool)
    _attach(tutor, course, 10)

    # Placed, it gets a gradebook column out of the test's points (an exercise that is no test gets none).
    status, _, picker = launch(tutor, lms, "tina-instructor", [INSTRUCTOR], deep_link=True)
    assert status == 200 and "Python exercise, a test of the course" in picker
    item = _place(tutor, lms, f"exercise:{SLUG}")
    assert item["lineItem"]["scoreMaximum"] == 10 and item["custom"]["telelab_target"] == f"exercise:{SLUG}"
    assert "lineItem" not in _place(tutor, lms, "exercise:bump-and-go")

    # The learner opens it from the LMS, which names the column's line item.
    learner = LabClient(tool.url)
    status, headers, _ = launch(learner, lms, "lu-learner", [LEARNER], custom=item["custom"],
                                lineitem=lms.url + "/lineitems/21")
    assert status == 303 and urlsplit(headers["Location"]).path == f"/exercises/{SLUG}"
    name = _username(tool, "lu-learner")

    # The LMS is down: the half mark waits, and the tutor reads why, in English and in Spanish.
    lms.fail_scores = 1000
    assert _submit(tool, name, closest_m=0.6) == 0.5
    page = wait_for(lambda: (p := tutor.request("GET", f"/courses/{course}")[2]) and "maintenance" in p and p)
    assert page, "the failed grade is not shown to the tutor"
    waiting = page[page.index('id="grades-waiting"'):]
    assert name in waiting and TITLE in waiting and "5 / 10" in waiting, waiting[:1500]
    assert "The LMS answered 503" in waiting and "tries: 1" in waiting
    spanish = tutor.request("GET", f"/courses/{course}", headers={"Accept-Language": "es"})[2]
    assert "Columna del libro de calificaciones" in spanish and "El LMS respondió 503" in spanish

    # A better submission meanwhile supersedes the waiting mark; once the LMS is back, "Retry now" sends only it.
    assert _submit(tool, name, closest_m=0.1) == 1.0
    assert [(score, status) for score, _, status in _passbacks(tool, name)] == [(5, "superseded"), (10, "pending")]
    lms.fail_scores = 0
    _retry(tutor, course)
    assert wait_for(lambda: lms.scores), "the grade never reached the LMS"
    assert len(lms.scores) == 1, lms.scores
    score = lms.scores[0]
    assert score["lineitem"] == "/lineitems/21" and score["userId"] == "lu-learner"
    assert (score["scoreGiven"], score["scoreMaximum"], score["gradingProgress"]) == (10, 10, "FullyGraded")
    page = wait_for(lambda: (p := tutor.request("GET", f"/courses/{course}")[2]) and "grades-waiting" not in p and p)
    assert page, "the sent grade is still shown as waiting"
    columns = page[page.index('id="grade-columns"'):page.index("</table>", page.index('id="grade-columns"'))]
    assert TITLE in columns and re.search(r">1</td>\s*<td[^>]*>0</td>", columns), columns

    # A worse submission changes no mark and sends nothing; new points make a new mark, sent at once.
    assert _submit(tool, name, closest_m=2.0) == 0.0
    _attach(tutor, course, 20)
    assert wait_for(lambda: len(lms.scores) == 2), "the new points' mark never reached the LMS"
    assert (lms.scores[1]["scoreGiven"], lms.scores[1]["scoreMaximum"]) == (20, 20)
    assert wait_for(lambda: [status for *_, status in _passbacks(tool, name)] == ["superseded", "sent", "sent"]), \
        _passbacks(tool, name)  # the LMS took it; the sender writes so once it has its answer


def test_a_submission_after_the_deadline_or_by_a_student_the_lms_does_not_know_sends_nothing(
        tool: LiveServer, lms: LmsPlatform) -> None:
    from middleware.auth.services import create_user
    from middleware.db import unit_of_work
    from middleware.models import CourseMembership

    course = _course_id(tool)
    with tool.app.app_context(), unit_of_work(tool.app) as session:  # enrolled by hand, never launched from the LMS
        local = create_user(session, "local-student", "student", "a-long-enough-secret")
        session.add(CourseMembership(course_id=course, user_id=local.id, role="student"))
    before = len(lms.scores)
    assert _submit(tool, "local-student", closest_m=0.1) == 1.0
    assert _passbacks(tool, "local-student") == []

    learner = LabClient(tool.url)  # known to the LMS, but too late
    assert launch(learner, lms, "late-learner", [LEARNER])[0] == 303
    late = _username(tool, "late-learner")
    assert _submit(tool, late, closest_m=0.1, started=datetime.now(UTC) + timedelta(days=8)) == 1.0
    assert _passbacks(tool, late) == []
    assert len(lms.scores) == before


def test_marks_made_before_the_lms_named_the_column_are_sent_when_it_does(tool: LiveServer,
                                                                        lms: LmsPlatform) -> None:
    lms.fail_scores = 0
    tutor = LabClient(tool.url)
    assert launch(tutor, lms, "tina-instructor", [INSTRUCTOR])[0] == 303
    course = _course_id(tool)
    _attach(tutor, course, 4, slug="wall-following")
    learner = LabClient(tool.url)
    assert launch(learner, lms, "early-learner", [LEARNER])[0] == 303  # the lab's home: known, enrolled
    early = _username(tool, "early-learner")
    _submit(tool, early, closest_m=0.1, slug="wall-following")
    assert _passbacks(tool, early) == []  # no column yet

    item = _place(tutor, lms, "exercise:wall-following")
    assert item["lineItem"]["scoreMaximum"] == 4
    before = len(lms.scores)
    assert launch(tutor, lms, "tina-instructor", [INSTRUCTOR], custom=item["custom"],
                  lineitem=lms.url + "/lineitems/33")[0] == 303  # anyone's launch names it: here the instructor's
    assert wait_for(lambda: len(lms.scores) > before), "the earlier mark never reached the LMS"
    sent = [s for s in lms.scores[before:] if s["lineitem"] == "/lineitems/33"]
    assert [s["userId"] for s in sent] == ["early-learner"]
    assert sent[0]["scoreMaximum"] == 4


def test_a_deadline_moved_before_the_submission_takes_back_the_mark_still_waiting(tool: LiveServer,
                                                                                  lms: LmsPlatform) -> None:
    tutor = LabClient(tool.url)
    assert launch(tutor, lms, "tina-instructor", [INSTRUCTOR])[0] == 303
    course = _course_id(tool)
    name = _username(tool, "lu-learner")  # 20 / 20 on the first test's exercise, sent
    lms.fail_scores = 1000
    _attach(tutor, course, 30)
    assert wait_for(lambda: (p := tutor.request("GET", f"/courses/{course}")[2]) and "maintenance" in p), \
        "the new points' mark did not wait with its reason"
    before = len(lms.scores)
    _attach(tutor, course, 30, days=-1)  # every submission now begun after the deadline: no mark
    assert _passbacks(tool, name)[-1] == (30, 30, "superseded")
    lms.fail_scores = 0
    _retry(tutor, course)
    page = wait_for(lambda: (p := tutor.request("GET", f"/courses/{course}")[2]) and "grades-waiting" not in p and p)
    assert page and len(lms.scores) == before  # the LMS keeps the 20 it had; nothing is sent for no mark
