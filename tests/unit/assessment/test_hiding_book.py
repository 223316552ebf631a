"""The process's book of who is in an obstacle-zone test answers "no" from a reading up to RECHECK_S old, but never
refuses from one: a student who submitted and reloaded at once had the camera refused (the end's announcement had
not reached the book yet), and the console does not ask again. The table is stubbed here (its query is tested in
tests/integration/assessment/test_obstacles_hidden_during_zone_test.py against the real database)."""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import UTC, datetime, timedelta

import pytest

from middleware.assessment import hidden_obstacles
from middleware.assessment.hidden_obstacles import HidingBook

STUDENT, OTHER = 7, 8
SESSION = object()  # the caller's session, passed through to the (stubbed) query


@dataclass
class Table:
    """Who has an obstacle-zone attempt in progress, as the database answers, and the reads asked of it."""

    rows: dict[int, datetime | None] = field(default_factory=lambda: {STUDENT: None})
    reads: list[int | None] = field(default_factory=list)

    def users_hiding_obstacles(self, _session, now: datetime, user_id: int | None = None) -> dict:
        self.reads.append(user_id)
        return {user: deadline for user, deadline in self.rows.items()
                if (user_id is None or user == user_id) and (deadline is None or deadline > now)}


@pytest.fixture
def table(monkeypatch: pytest.MonkeyPatch) -> Table:
    stub = Table()
    monkeypatch.setattr(hidden_obstacles, "users_hiding_obstacles", stub.users_hiding_obstacles)
    return stub


def book() -> HidingBook:
    return HidingBook(lambda: None, recheck_s=60.0)  # type: ignore[arg-type,return-value]


def test_an_attempt_that_ended_before_its_announcement_came_refuses_nothing(table: Table) -> None:
    hiding = book()
    assert hiding.hides(STUDENT, SESSION)  # type: ignore[arg-type]
    del table.rows[STUDENT]  # submitted; the announcement has not reached this process yet
    assert not hiding.hides(STUDENT, SESSION)  # type: ignore[arg-type]


def test_people_not_in_a_test_are_answered_from_the_reading_without_a_read_each(table: Table) -> None:
    hiding = book()
    for _ in range(50):
        assert not hiding.hides(OTHER, SESSION)  # type: ignore[arg-type]
    assert table.reads == [None]


def test_a_student_still_in_the_test_stays_refused_until_the_deadline_passes(table: Table) -> None:
    hiding = book()
    table.rows[STUDENT] = datetime.now(UTC) + timedelta(hours=1)
    assert hiding.hides(STUDENT, SESSION)  # type: ignore[arg-type]
    assert hiding.hides(STUDENT, SESSION)  # type: ignore[arg-type]
    assert table.reads == [None, STUDENT]  # the second "yes" was read for that student alone
    table.rows[STUDENT] = datetime.now(UTC) - timedelta(seconds=1)
    assert not hiding.hides(STUDENT, SESSION)  # type: ignore[arg-type]
