"""The suite's `alone` tests (tests/conftest.py): one waits for the other processes' running tests to end, the others
start none while it runs, and a stream of others taking turns does not keep it waiting for ever."""

from __future__ import annotations

import threading
import time

import pytest

from tests.conftest import MachineShare, share_of_the_machine


@pytest.fixture
def suite_run(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    monkeypatch.setenv("PYTEST_XDIST_TESTRUNUID", f"lock-test-{time.monotonic_ns()}")
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))


def test_an_alone_test_waits_for_the_running_ones_and_holds_the_others_back(suite_run) -> None:
    events: list[str] = []
    others_running, release_others = threading.Event(), threading.Event()

    def other(name: str) -> None:
        with share_of_the_machine(alone=False):
            events.append(f"{name} runs")
            others_running.set()
            release_others.wait(5)
            events.append(f"{name} ends")

    def alone() -> None:
        with share_of_the_machine(alone=True):
            events.append("alone runs")
            time.sleep(0.2)
            events.append("alone ends")

    first = threading.Thread(target=other, args=("first",))
    first.start()
    others_running.wait(5)
    lonely = threading.Thread(target=alone)
    lonely.start()
    time.sleep(0.2)
    later = threading.Thread(target=other, args=("later",))  # arrives while alone waits: it must wait for alone
    later.start()
    time.sleep(0.2)
    assert events == ["first runs"], events
    release_others.set()
    for thread in (first, lonely, later):
        thread.join(5)
    assert events == ["first runs", "first ends", "alone runs", "alone ends", "later runs", "later ends"], events


def test_others_taking_overlapping_turns_do_not_starve_an_alone_test(suite_run) -> None:
    stop, ran_alone = threading.Event(), threading.Event()

    def others_in_turn() -> None:
        while not stop.is_set():
            with share_of_the_machine(alone=False):
                time.sleep(0.05)

    def alone() -> None:
        with share_of_the_machine(alone=True):
            ran_alone.set()

    turns = [threading.Thread(target=others_in_turn, daemon=True) for _ in range(3)]
    for thread in turns:
        thread.start()
    time.sleep(0.1)
    waiter = threading.Thread(target=alone, daemon=True)
    began = time.monotonic()
    waiter.start()
    got_it = ran_alone.wait(2.0)
    waited_s = time.monotonic() - began
    stop.set()
    for thread in (waiter, *turns):
        thread.join(5)
    assert got_it and waited_s < 1.0, "the alone test waited while others took overlapping turns"


def test_a_marked_test_followed_by_another_keeps_the_machine_for_it(suite_run) -> None:
    events: list[str] = []
    machine = MachineShare()
    machine.take(alone=True)

    def other() -> None:
        with share_of_the_machine(alone=False):
            events.append("other runs")

    waiting = threading.Thread(target=other)
    waiting.start()
    time.sleep(0.2)
    began = time.monotonic()
    machine.take(alone=True)  # the next marked test: no turn is given away in between
    assert time.monotonic() - began < 0.1 and events == []
    time.sleep(0.2)
    assert events == [], "another test ran between two marked ones"
    machine.give_back()
    waiting.join(5)
    assert events == ["other runs"]
