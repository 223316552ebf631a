"""The demo class `telelab up` seeds (issue 31): the demo tutor's course in session, four students on robots of their
own, a raised hand and the class chat on the wall; seeded once, and a later start only starts its robots again."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import _let_go


def test_the_demo_class_shows_tiles_a_raised_hand_and_the_chat_and_is_seeded_once(
        tmp_path: Path, skill_server_address: str) -> None:
    from sqlalchemy import select

    from middleware.chat.services import recent_messages
    from middleware.db import session_factory
    from middleware.demo_course import DEMO_COURSE_CODE
    from middleware.lab_runner import ensure_demo_accounts, seed_demo_course
    from middleware.models import Course
    from middleware.teaching import class_sessions, class_wall
    from middleware.teaching.class_wall_live import chat_room
    from middleware.teaching.demo_class import DEMO_CHAT, DEMO_HAND, DEMO_PUPILS, seed_demo_class
    from middleware.teaching.practice_robots import practice_manager
    from tests.conftest import make_test_app

    app = make_test_app(f"sqlite:///{tmp_path / 'demo.sqlite3'}", f"lab-1={skill_server_address}", tmp_path)
    try:
        ensure_demo_accounts(app)
        seed_demo_course(app)
        assert seed_demo_class(app)
        with session_factory(app)() as session:
            course_id = session.scalar(select(Course.id).where(Course.code == DEMO_COURSE_CODE))
            opened = class_sessions.open_session(session, course_id)
            assert opened is not None
            seats = class_wall.wall_seats(session, opened.id)
            assert sorted(seat.username for seat in seats) == sorted(["student", *DEMO_PUPILS])
            assert all(seat.seat_state == "ready" for seat in seats), [(s.username, s.message) for s in seats]
            hands = {seat.username: seat.hand for seat in seats if seat.hand}
            assert hands == {DEMO_HAND[0]: {"text": DEMO_HAND[1], "raised_at": hands[DEMO_HAND[0]]["raised_at"]}}
            room = chat_room(opened.id)
            said = [(message.author_username, message.body) for message in recent_messages(session, room)]
            assert said == list(DEMO_CHAT)
        assert seed_demo_class(app) == []  # once: every robot still runs, nothing more to do
        practice_manager(app).stop(seats[0].user_id)  # an earlier lab's robot, gone with its farm
        assert seed_demo_class(app) == ["the demo class's robots started again (1)"]
        with session_factory(app)() as session:
            assert all(seat.seat_state == "ready" for seat in class_wall.wall_seats(session, opened.id))
            assert len(recent_messages(session, chat_room(opened.id))) == len(DEMO_CHAT)
    finally:
        practice_manager(app).shutdown()
        _let_go(app)  # its ticker, links, farm and practice keeper
        session_factory(app).kw["bind"].dispose()
