"""`telelab up` seeds the demo course once: the demo student can book and has a quiz, a timed test and an
experimental test (issue 14, failure 5); a second start, or a database from before the course, never duplicates."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

from sqlalchemy import func, select


def _counts(app) -> dict[str, object]:
    from middleware.db import session_factory
    from middleware.models import Course, CourseMembership
    from middleware.models.assessment import Exam, Question

    with session_factory(app)() as session:
        return {
            "courses": session.scalar(select(func.count()).select_from(Course)),
            "members": sorted(session.execute(select(CourseMembership.role, func.count())
                                              .group_by(CourseMembership.role)).all()),
            "questions": session.scalar(select(func.count()).select_from(Question)),
            "exams": sorted(session.scalars(select(Exam.kind))),
        }


def test_seeding_twice_gives_one_course_with_its_people_and_tests(app, demo_accounts) -> None:
    from middleware.demo_course import DEMO_ALLOWANCE_MIN, DEMO_COURSE_CODE, DEMO_COURSE_TITLE, DEMO_QUESTIONS
    from middleware.lab_runner import seed_demo_course

    assert set(demo_accounts) == {"student", "tutor", "admin"}
    added = seed_demo_course(app)
    assert any(DEMO_COURSE_TITLE in item for item in added) and "the demo student enrolled" in added
    first = _counts(app)
    # the demo student and 3 survey classmates; quizzes: the practice one, the lesson's before and after
    assert first == {"courses": 1, "members": [("student", 4), ("tutor", 1)], "questions": len(DEMO_QUESTIONS),
                     "exams": ["experimental", "quiz", "quiz", "quiz", "theory"]}
    assert seed_demo_course(app) == []
    assert _counts(app) == first

    from middleware.db import session_factory
    from middleware.models import Course

    with session_factory(app)() as session:
        course = session.scalar(select(Course).where(Course.code == DEMO_COURSE_CODE))
        assert course is not None and course.title == "Mobile robotics (demo)"
        assert course.booking_allowance_min == DEMO_ALLOWANCE_MIN


def test_an_older_database_with_the_accounts_but_no_course_gets_it_at_the_next_start(app) -> None:
    from middleware.lab_runner import ensure_demo_accounts, seed_demo_course

    assert seed_demo_course(app) == []  # no demo tutor yet: nothing to seed, and no half course left behind
    assert _counts(app)["courses"] == 0
    ensure_demo_accounts(app)  # what an older `telelab up` left: the accounts, no course
    assert seed_demo_course(app)
    assert _counts(app)["courses"] == 1


def test_the_seeded_student_can_book_and_sees_every_kind_of_test_open_now(app, demo_accounts) -> None:
    from middleware.assessment import bank
    from middleware.assessment.attempts import window_state
    from middleware.auth.services import find_user
    from middleware.bookings.schemas import BookingRequest
    from middleware.bookings.services import create_booking
    from middleware.db import session_factory
    from middleware.lab_runner import seed_demo_course

    seed_demo_course(app)
    now = datetime.now(UTC)
    start = now.replace(minute=0, second=0, microsecond=0) + timedelta(days=1)
    with session_factory(app)() as session:
        student = find_user(session, "student")
        booking = create_booking(session, student, BookingRequest("lab-1", start, start + timedelta(minutes=60),
                                                                  "personal", None), now)
        assert booking.course_id is not None
        exams = bank.list_exams(session, booking.course_id)
        assert {exam.kind: window_state(exam, now) for exam in exams} == {
            "quiz": "open", "theory": "open", "experimental": "open"}
        experimental = next(exam for exam in exams if exam.kind == "experimental")
        assert experimental.robot_name == "lab-1" and experimental.task["kind"] == "reach_point"
        session.commit()


def test_seeding_leaves_what_the_tutor_changed_since(app, demo_accounts) -> None:
    from middleware.auth.services import find_user
    from middleware.courses.services import unenrol
    from middleware.db import session_factory
    from middleware.demo_course import seed_demo_course as seed
    from middleware.lab_runner import seed_demo_course

    seed_demo_course(app)
    with session_factory(app)() as session:
        course_id = seed(session).course_id
        assert course_id is not None
        unenrol(session, find_user(session, "tutor"), course_id, find_user(session, "student").id)
        session.commit()
    assert seed_demo_course(app) == []
    assert _counts(app)["members"] == [("student", 3), ("tutor", 1)]


def test_the_demo_tutor_sees_the_survey_charts_and_the_demo_student_may_still_answer(app, demo_accounts) -> None:
    from middleware.assessment import survey
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.demo_course import DEMO_SURVEY_ANSWERS
    from middleware.demo_course import seed_demo_course as seed
    from middleware.lab_runner import seed_demo_course

    seed_demo_course(app)
    with session_factory(app)() as session:
        course_id = seed(session).course_id
        results = survey.results(session, find_user(session, "tutor"), course_id)
        assert results.respondents == survey.MIN_RESPONDENTS and not results.hidden
        assert [item.total for item in results.items] == [len(DEMO_SURVEY_ANSWERS)] * len(results.items)
        assert not survey.has_answered(session, find_user(session, "student").id, course_id)
        assert not any(find_user(session, name).is_active for name in DEMO_SURVEY_ANSWERS)  # nobody logs in as them


def test_a_demo_course_seeded_before_the_classmates_gets_them_once(app, demo_accounts, monkeypatch) -> None:
    import middleware.demo_course as demo
    from middleware.assessment import survey
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.lab_runner import seed_demo_course

    with monkeypatch.context() as older:  # what an older `telelab up` seeded: the course, no classmates
        older.setattr(demo, "_survey_classmates", lambda *_args: [])
        assert seed_demo_course(app)
    assert seed_demo_course(app) == [f"the lab survey answered by {len(demo.DEMO_SURVEY_ANSWERS)} demo classmates",
                                     f"{len(demo.DEMO_TRIALS) * 5} experiment trials of theirs on course-A"]
    assert seed_demo_course(app) == []
    with session_factory(app)() as session:
        course_id = demo.seed_demo_course(session).course_id
        assert survey.results(session, find_user(session, "tutor"), course_id).respondents == 3


def test_the_demo_student_reads_the_open_leaderboard_of_the_course_s_exercise_test(app, demo_accounts) -> None:
    from middleware.auth.services import find_user
    from middleware.db import session_factory
    from middleware.demo_course import DEMO_EXERCISE
    from middleware.demo_course import seed_demo_course as seed
    from middleware.exercises import leaderboard, services
    from middleware.lab_runner import seed_demo_course

    seed_demo_course(app)
    with session_factory(app)() as session:
        course_id = seed(session).course_id
        assert course_id is not None
        exercise = services.exercise_by_slug(session, DEMO_EXERCISE)
        board = leaderboard.leaderboard(session, find_user(session, "student"), course_id, exercise)
        assert board["open"] and not board["may_open"]
        # Round the pillar to the goal, short of it, and stopped before the pillar: full, half and no marks.
        assert [(row["username"], row["mark"], row["you"]) for row in board["standings"]] == [
            ("demo-classmate-1", 10.0, False), ("demo-classmate-2", 5.0, False), ("demo-classmate-3", 0.0, False)]
        assert board["unranked"] == 1  # the demo student, who has not submitted yet
    assert seed_demo_course(app) == []
