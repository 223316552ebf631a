"""An instructor's first launch from an LMS course Telelab does not know yet, when they already tutor a Telelab
course no LMS course is linked to: they choose that course (its students, tests and grades then shared with the LMS
course) or a new one, and the launch goes on where it was going. Without such a course the LMS course gets a new
Telelab course at once, as before (test_launches.py)."""

from __future__ import annotations

from sqlalchemy import func, select

from tests.conftest import LabClient, LiveServer, make_course
from tests.integration.lti.conftest import launch
from tests.integration.lti.platform import INSTRUCTOR, LEARNER, LmsPlatform
from tests.integration.lti.test_services import _inputs


def _linked(tool: LiveServer, context: str) -> int | None:
    from middleware.db import session_factory
    from middleware.models.lti import LtiContext

    with session_factory(tool.app)() as session:
        return session.scalar(select(LtiContext.course_id).where(LtiContext.context_id == context))


def _tutor_of_a_local_course(tool: LiveServer, lms: LmsPlatform, subject: str, code: str) -> tuple[LabClient, int]:
    """An LMS instructor whose Telelab account an admin made a tutor of a course of the lab's own."""
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.lti import LtiIdentity

    client = LabClient(tool.url)
    assert launch(client, lms, subject, [INSTRUCTOR], context="term-1-" + subject)[0] == 303
    with session_factory(tool.app)() as session:
        username = session.scalar(select(User.username).join(LtiIdentity, LtiIdentity.user_id == User.id)
                                  .where(LtiIdentity.subject == subject))
    return client, make_course(tool.app, code, {username: "tutor"})


def test_an_instructor_links_a_new_lms_course_to_one_of_their_courses(tool: LiveServer, lms: LmsPlatform) -> None:
    from middleware.models import Course

    teacher, local = _tutor_of_a_local_course(tool, lms, "lina-instructor", "LAB-LOCAL")
    status, _, page = launch(teacher, lms, "lina-instructor", [INSTRUCTOR], context="term-2")
    assert status == 200 and 'id="link-course-form"' in page and "Course LAB-LOCAL" in page
    assert "Mobile robotics is new to Telelab" in page
    assert _linked(tool, "term-2") is None  # nothing made before the choice
    form = _inputs(page)

    intruder = LabClient(tool.url)  # another instructor cannot answer someone else's choice
    assert launch(intruder, lms, "ivo-instructor", [INSTRUCTOR], context="term-9")[0] == 303
    status, _, refused = intruder.request("POST", "/lti/link-course", {
        "csrf_token": intruder.csrf_token("/account/password"), "launch_id": form["launch_id"], "course": str(local)})
    assert status == 403 and "someone else" in refused and _linked(tool, "term-2") is None

    status, _, again = teacher.request("POST", "/lti/link-course", {  # a course that is not theirs to link
        "csrf_token": form["csrf_token"], "launch_id": form["launch_id"], "course": "999999"})
    assert status == 400 and "Choose one of your courses" in again and _linked(tool, "term-2") is None

    status, headers, _ = teacher.request("POST", "/lti/link-course", {
        "csrf_token": form["csrf_token"], "launch_id": form["launch_id"], "course": str(local)})
    assert status == 303 and headers["Location"].endswith("/lab")
    assert _linked(tool, "term-2") == local

    learner = LabClient(tool.url)  # the LMS course's learners now join the linked course
    assert launch(learner, lms, "leo-learner", [LEARNER], context="term-2")[0] == 303
    from middleware.db import session_factory
    from middleware.models import CourseMembership

    with session_factory(tool.app)() as session:
        members = session.scalar(select(func.count()).select_from(CourseMembership)
                                 .where(CourseMembership.course_id == local))
        assert members == 2 and session.get(Course, local).code == "LAB-LOCAL"
    # Its next launch from that LMS course goes straight in: the choice is made once.
    assert launch(teacher, lms, "lina-instructor", [INSTRUCTOR], context="term-2")[0] == 303


def test_an_instructor_may_choose_a_new_course_for_the_new_lms_course(tool: LiveServer, lms: LmsPlatform) -> None:
    teacher, local = _tutor_of_a_local_course(tool, lms, "nora-instructor", "NORA-LOCAL")
    status, _, page = launch(teacher, lms, "nora-instructor", [INSTRUCTOR], context="term-3", deep_link=True)
    assert status == 200 and 'id="link-course-form"' in page
    form = _inputs(page)
    status, _, picker = teacher.request("POST", "/lti/link-course", {
        "csrf_token": form["csrf_token"], "launch_id": form["launch_id"], "course": "new"})
    assert status == 200 and 'id="deep-link-form"' in picker  # a deep-linking launch goes on to the picker
    made = _linked(tool, "term-3")
    assert made is not None and made != local
