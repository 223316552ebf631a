"""A course's leaderboard of an exercise test over HTTP, on SQLite and PostgreSQL: the course's students ranked by
their mark (the best graded submission begun before the deadline), equal marks by who reached theirs first, students
with no mark counted and not named; closed by default, opened and closed by the course's tutors; while closed a
student is refused it (in their language), once open only the course's members read it. The graded runs are made
through the exercises' services with a pose log given by the test: no robot runs here."""

from __future__ import annotations

from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from tests.conftest import LiveServer, _let_go, add_test_account, make_test_app
from tests.integration.bookings.conftest import api
from tests.integration.plans.conftest import PlansLab

DEADLINE = datetime(2026, 3, 10, 12, 0, tzinfo=UTC)
GOAL = {"kind": "reach_goal", "x_m": 2.0, "y_m": 0.0, "radius_m": 0.4}
EXERCISE = {"slug": "reach-the-box", "title": "Reach the box", "statement": "Drive to the box.",
            "template": "from telelab import robot\n", "scene": "lab", "start": [0.0, 0.0, 0.0],
            "random_starts": None, "time_limit_s": 30.0, "rubric": GOAL}
# Where a run ends, and the fraction reach_goal gives it: on the goal 1, within twice its radius 0.5, else 0.
FULL, HALF = 2.0, 1.4
PEOPLE = {"tutor1": "tutor", "tutor2": "tutor", "admin1": "admin", "ann": "student", "bea": "student",
          "cai": "student", "dov": "student", "eve": "student"}
SPANISH = {"Accept-Language": "es-ES,es;q=0.9"}


def address(lab: PlansLab, course_id: int | None = None, slug: str = "reach-the-box") -> str:
    """The leaderboard's API address of slug in ROB1 (or course_id)."""
    return f"/api/courses/{course_id or lab.course}/exercises/{slug}/leaderboard"


def submit(session, user, exercise, started_at: datetime, end_x_m: float, mode: str = "submission") -> None:
    """A run of user's begun at started_at and graded, as the page's Submit does, from a pose log ending at x."""
    from middleware.exercises import services

    code = services.save_code(session, user, exercise, f"# {started_at.isoformat()}\n", started_at)
    trace = [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [5.0, end_x_m, 0.0, 0.0, end_x_m, 0.0, 0.0]]
    run = services.begin_run(session, user, exercise, code, mode, f"practice-{user.username}", "lab",
                             lambda start: None, lambda: started_at, lambda *_: trace)
    services.finish_run(session, user, run, None, lambda *_: trace, started_at + timedelta(seconds=20))


@pytest.fixture
def board(database_url: str, tmp_path: Path) -> Iterator[PlansLab]:
    """Course ROB1 (tutor1; ann, bea, cai, dov) with the exercise as a test, ROB2 (tutor2; eve), served."""
    from middleware.db import session_factory
    from middleware.exercises import schemas, services
    from middleware.models import Course, CourseMembership

    app = make_test_app(database_url, "", tmp_path)
    with app.app_context(), session_factory(app)() as session:
        users = {name: add_test_account(session, name, role) for name, role in PEOPLE.items()}
        course, other = Course(code="ROB1", title="Course ROB1"), Course(code="ROB2", title="Course ROB2")
        session.add_all([course, other])
        session.flush()
        for name, where, role in [("tutor1", course, "tutor"), ("ann", course, "student"), ("bea", course, "student"),
                                  ("cai", course, "student"), ("dov", course, "student"), ("tutor2", other, "tutor"),
                                  ("eve", other, "student")]:
            session.add(CourseMembership(course_id=where.id, user_id=users[name].id, role=role))
        session.flush()
        exercise = services.add_exercise(session, users["tutor1"], schemas.definition(EXERCISE))
        services.attach_to_course(session, users["tutor1"], course.id, exercise, DEADLINE, 10.0)
        services.attach_to_course(session, users["tutor2"], other.id, exercise, DEADLINE, 10.0)

        def before(**ahead: float) -> datetime:
            return DEADLINE - timedelta(**ahead)

        # ann: half, then full marks 3 h before the deadline (again 30 min before: she reached them at the first).
        # bea: nothing, then full marks 2 h before, so she ranks after ann. cai: half before the deadline, full marks
        # only after it. dov: only practice. eve, of the other course, has full marks and is not in ROB1's ranking.
        submit(session, users["ann"], exercise, before(hours=5), HALF)
        submit(session, users["ann"], exercise, before(hours=3), FULL)
        submit(session, users["ann"], exercise, before(minutes=30), FULL)
        submit(session, users["bea"], exercise, before(hours=4), 0.0)
        submit(session, users["bea"], exercise, before(hours=2), FULL)
        submit(session, users["cai"], exercise, before(hours=1), HALF)
        submit(session, users["cai"], exercise, DEADLINE + timedelta(minutes=1), FULL)
        submit(session, users["dov"], exercise, before(hours=6), FULL, mode="practice")
        submit(session, users["eve"], exercise, before(hours=7), FULL)
        session.commit()
        course_id, other_id = course.id, other.id
    server = LiveServer(app)
    try:
        yield PlansLab(server, course_id, other_id)
    finally:
        server.stop()
        _let_go(app)
        session_factory(app).kw["bind"].dispose()  # before the PostgreSQL database is dropped


def test_students_rank_by_their_mark_before_the_deadline_and_equal_marks_by_who_reached_it_first(
        board: PlansLab) -> None:
    status, answer = api(board.client("tutor1"), "GET", address(board))

    assert status == 200, answer
    assert (answer["open"], answer["may_open"], answer["points"]) == (False, True, 10.0)
    assert answer["deadline_at"] == DEADLINE.isoformat()
    assert [(s["rank"], s["username"], s["mark"], s["fraction"], s["reached_at"], s["you"])
            for s in answer["standings"]] == [
        (1, "ann", 10.0, 1.0, (DEADLINE - timedelta(hours=3)).isoformat(), False),
        (2, "bea", 10.0, 1.0, (DEADLINE - timedelta(hours=2)).isoformat(), False),
        (3, "cai", 5.0, 0.5, (DEADLINE - timedelta(hours=1)).isoformat(), False),
    ]
    assert answer["unranked"] == 1  # dov, whose only run was practice: counted, not named

    # The class view links the tutor to it and says it is closed.
    status, _, page = board.client("tutor1").request("GET", "/exercises/reach-the-box/class")
    assert status == 200
    assert f'href="/courses/{board.course}/exercises/reach-the-box/leaderboard"' in page
    assert "Leaderboard (closed to the students)" in page


def test_a_closed_leaderboard_is_refused_to_students_and_an_open_one_shown_to_the_courses_members_only(
        board: PlansLab) -> None:
    ann, eve, tutor1, tutor2 = (board.client(name) for name in ("ann", "eve", "tutor1", "tutor2"))
    status, answer = api(ann, "GET", address(board))
    assert (status, answer["error"]["code"], answer["error"]["field"]) == (403, "leaderboard_closed", "slug")
    assert answer["error"]["message"] == \
        "Your tutor has not opened this leaderboard; your own mark is on the exercise's page."
    status, answer = api(ann, "GET", address(board), extra_headers=SPANISH)
    assert (status, answer["error"]["code"]) == (403, "leaderboard_closed")
    assert answer["error"]["message"].startswith("Tu tutor aún no ha abierto esta clasificación")
    # The page itself is the course members' (it says the refusal once it asks); the exercise page has no link yet.
    status, _, page = ann.request("GET", f"/courses/{board.course}/exercises/reach-the-box/leaderboard")
    assert status == 200 and 'data-slug="reach-the-box"' in page
    assert 'data-action="leaderboard"' not in ann.request("GET", "/exercises/reach-the-box")[2]

    # Only the course's tutors (and admins) open it; the body is checked.
    for client, expected in ((ann, (403, "forbidden")), (tutor2, (403, "forbidden"))):
        status, answer = api(client, "PUT", address(board), {"open": True})
        assert (status, answer["error"]["code"], answer["error"]["field"]) == (*expected, "course_id")
    status, answer = api(tutor1, "PUT", address(board), {"open": "yes"})
    assert (status, answer["error"]["field"]) == (400, "open")
    status, answer = api(tutor1, "PUT", address(board), {"open": True})
    assert (status, answer) == (200, {"open": True})

    status, answer = api(ann, "GET", address(board))
    assert status == 200 and answer["open"] and not answer["may_open"]
    assert [(s["username"], s["you"]) for s in answer["standings"]] == [("ann", True), ("bea", False), ("cai", False)]
    _, _, page = ann.request("GET", "/exercises/reach-the-box")
    assert f'href="/courses/{board.course}/exercises/reach-the-box/leaderboard" data-action="leaderboard"' in page
    status, answer = api(board.client("admin1"), "GET", address(board))
    assert status == 200 and answer["may_open"]

    # A student or tutor of another course is refused it, page and API alike.
    for client in (eve, tutor2):
        status, answer = api(client, "GET", address(board))
        assert (status, answer["error"]["code"], answer["error"]["field"]) == (403, "not_in_course", "course_id")
        status, headers, _ = client.request("GET", f"/courses/{board.course}/exercises/reach-the-box/leaderboard")
        assert status == 403 and headers["Content-Type"].startswith("text/html")
    # ROB2's own leaderboard stays closed to eve: each test's leaderboard is opened on its own.
    status, answer = api(eve, "GET", address(board, board.other_course))
    assert (status, answer["error"]["code"]) == (403, "leaderboard_closed")

    # Closed again, the students are refused again; an exercise that is no test of a course has no leaderboard.
    status, answer = api(tutor1, "PUT", address(board), {"open": False})
    assert (status, answer) == (200, {"open": False})
    assert api(ann, "GET", address(board))[0] == 403
    status, answer = api(tutor1, "GET", address(board, slug="bump-and-go"))
    assert (status, answer["error"]["code"], answer["error"]["field"]) == (404, "not_a_test", "slug")
    status, answer = api(tutor1, "GET", address(board, 999999))
    assert (status, answer["error"]["field"]) == (404, "course_id")
