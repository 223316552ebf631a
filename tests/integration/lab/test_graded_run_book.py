"""The sockets that show the truth ask every second whether their viewer's graded run began: the process answers them
all from one read a second (a class of 50 asked a hundred queries a second of the sockets' pool, which the drive
commands share), and a run that begins is still seen within GRADED_RUN_RECHECK_S."""

from __future__ import annotations

import time
from pathlib import Path

from tests.conftest import _let_go


def test_every_socket_is_answered_from_one_read_a_second_and_a_new_run_is_seen(
        tmp_path: Path, skill_server_address: str) -> None:
    from sqlalchemy import event

    from middleware.db import session_factory
    from middleware.lab.sockets import GRADED_RUN_RECHECK_S, GradedRunBook
    from middleware.models import User
    from middleware.models.experiment import TRIAL_OPEN, Trial
    from tests.conftest import make_test_app

    app = make_test_app(f"sqlite:///{tmp_path / 'book.sqlite3'}", f"lab-1={skill_server_address}", tmp_path)
    engine = session_factory(app).kw["bind"]
    statements: list[str] = []
    event.listen(engine, "before_cursor_execute", lambda *args: statements.append(args[2]))
    try:
        with session_factory(app)() as session:
            student = session.query(User).first()
            assert student is not None
            student_id = student.id
        book = GradedRunBook(app)
        assert not book.holds("lab-1", student_id)
        statements.clear()
        for viewer in range(100):  # a class's sockets asking within one second
            assert not book.holds("lab-1", student_id if viewer % 2 else viewer + 1000)
        assert statements == []  # answered from the read just made (before: two queries a socket)
        with session_factory(app)() as session:
            session.add(Trial(user_id=student_id, robot_name="lab-1", status=TRIAL_OPEN, course="course-A",
                              delay_s=0.0, feedback=False))
            session.commit()
        deadline = time.monotonic() + GRADED_RUN_RECHECK_S + 0.5
        while not book.holds("lab-1", student_id) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert book.holds("lab-1", student_id), "a run that began was not seen within the recheck"
        assert not book.holds("lab-2", student_id)
        assert len([s for s in statements if s.lstrip().upper().startswith("SELECT")]) <= 2 * 2 + 2
    finally:
        _let_go(app)  # its ticker, links, farm and practice keeper
        engine.dispose()
