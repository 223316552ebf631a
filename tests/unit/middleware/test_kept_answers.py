"""events.KeptAnswers: an answer is kept until its topic's announcement drops it (its key, or every answer), never
longer than its reader allows, briefly where announcements may go unheard, and not at all when its key (or every
answer) was dropped while it was read (a read that raced a change never outlives the change's announcement)."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from sqlalchemy import Engine, create_engine

from middleware.events import KeptAnswers, bus_of


@pytest.fixture
def engine() -> Iterator[Engine]:
    engine = create_engine("sqlite://")  # its bus reaches this process only: answers are kept short_s
    yield engine
    engine.dispose()


def test_an_answer_is_kept_until_its_key_is_announced(engine: Engine) -> None:
    kept: KeptAnswers[str, int] = KeptAnswers(engine, "things", short_s=60.0, heard_s=60.0)
    reads: list[str] = []
    assert kept.known("a") == (False, None)
    assert kept.get("a", lambda: reads.append("a") or 1) == 1
    assert kept.get("b", lambda: reads.append("b") or 2) == 2
    assert kept.get("a", lambda: reads.append("a") or 9) == 1 and kept.known("a") == (True, 1)
    bus_of(engine).deliver("things", "a")
    assert kept.known("a") == (False, None) and kept.known("b") == (True, 2)
    bus_of(engine).deliver("other-topic", "b")
    assert kept.known("b") == (True, 2)
    bus_of(engine).deliver("", None)  # a listener that reconnected: everything is read again
    assert kept.known("b") == (False, None)
    assert reads == ["a", "b"]


def test_an_unkeyed_topic_drops_every_answer(engine: Engine) -> None:
    kept: KeptAnswers[str, int] = KeptAnswers(engine, "classes", short_s=60.0, heard_s=60.0, keyed=False)
    kept.get("robot-1", lambda: 1)
    kept.get("robot-2", lambda: 2)
    bus_of(engine).deliver("classes", "17")  # announced with a class's id, not a robot's name
    assert kept.known("robot-1") == (False, None) and kept.known("robot-2") == (False, None)


@pytest.mark.parametrize("announced", [("things", "a"), ("", None)], ids=["its key", "a reconnected listener"])
def test_an_answer_read_while_its_key_was_dropped_is_given_but_not_kept(engine: Engine, announced) -> None:
    kept: KeptAnswers[str, str] = KeptAnswers(engine, "things", short_s=60.0, heard_s=60.0)

    def read_racing_a_change() -> str:
        bus_of(engine).deliver(*announced)  # the change commits and is announced while this reads
        return "before the change"

    assert kept.get("a", read_racing_a_change) == "before the change"
    assert kept.known("a") == (False, None)


def test_an_answer_lives_no_longer_than_its_reader_allows_nor_short_s_unheard(engine: Engine) -> None:
    kept: KeptAnswers[str, int | None] = KeptAnswers(engine, "things", short_s=0.2, heard_s=60.0)
    kept.get("none", lambda: None, lambda answer: 0.0 if answer is None else 60.0)
    assert kept.known("none") == (False, None), "an answer its reader keeps 0 s is not kept"
    kept.get("one", lambda: 1)
    assert kept.known("one") == (True, 1)
    time.sleep(0.25)
    assert kept.known("one") == (False, None), "kept past short_s where announcements go unheard"


def test_an_answer_read_while_another_key_was_dropped_is_kept(engine: Engine) -> None:
    kept: KeptAnswers[str, str] = KeptAnswers(engine, "things", short_s=60.0, heard_s=60.0)

    def read_while_another_changes() -> str:
        bus_of(engine).deliver("things", "b")  # another robot of the class started meanwhile
        return "a's answer"

    assert kept.get("a", read_while_another_changes) == "a's answer"
    assert kept.known("a") == (True, "a's answer")


def test_a_read_outlasting_more_drops_than_are_remembered_is_not_kept(engine: Engine) -> None:
    from middleware.events import RECENT_DROPS

    kept: KeptAnswers[str, str] = KeptAnswers(engine, "things", short_s=60.0, heard_s=60.0)

    def read_while_many_change() -> str:
        for index in range(RECENT_DROPS + 1):
            bus_of(engine).deliver("things", f"other-{index}")
        return "maybe stale"

    assert kept.get("a", read_while_many_change) == "maybe stale"
    assert kept.known("a") == (False, None)
