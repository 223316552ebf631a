"""The delay queue (ordering, bounds, refusals) and the experiment's statistics and CSV."""

from __future__ import annotations

import json
import math
import struct
import time

import pytest

from middleware.auth.schemas import InvalidField
from middleware.experiment.delay import (
    DelayBook,
    DelayQueue,
    Delays,
    ViewerDelay,
    capture_time_s,
    delay_in_force_s,
    parse_delay_s,
)
from middleware.experiment.services import results_csv, summarise
from middleware.models.experiment import Trial


@pytest.mark.parametrize("hostile", [-0.1, 7.01, 1e9, math.nan, math.inf, -math.inf, "3", None, True, [1], {}])
def test_absurd_or_non_numeric_delays_are_refused_naming_the_field(hostile: object) -> None:
    with pytest.raises(InvalidField) as refused:
        parse_delay_s(hostile)
    assert refused.value.field == "delay_s"


@pytest.mark.parametrize("good", [0, 0.0, 1, 3.5, 7])
def test_delays_from_0_to_7_seconds_are_taken(good: float) -> None:
    assert parse_delay_s(good) == pytest.approx(good)


def test_messages_are_held_until_capture_plus_delay_in_arrival_order() -> None:
    queue = DelayQueue(2.0)
    queue.push("a", 100.0, now_s=100.1)
    queue.push("b", 100.5, now_s=100.6)
    queue.push("c", 100.4, now_s=100.7)  # the robot's clock stepped back: c still comes after b
    assert queue.pop_due(101.9) == []
    assert queue.seconds_until_next(101.9) == pytest.approx(0.1)
    assert queue.pop_due(102.0) == ["a"]
    assert queue.pop_due(102.5) == ["b", "c"]
    assert queue.seconds_until_next(103.0) is None
    queue.push("late", None, now_s=200.0)  # no capture time: the arrival time counts
    assert queue.pop_due(201.9) == [] and queue.pop_due(202.0) == ["late"]


def test_the_queue_is_bounded_in_messages_and_bytes_dropping_the_oldest() -> None:
    queue = DelayQueue(7.0, max_messages=5, max_bytes=1000)
    for i in range(8):
        queue.push(f"m{i}", float(i), now_s=float(i))
    assert len(queue) == 5 and queue.dropped == 3
    assert queue.pop_due(100.0) == ["m3", "m4", "m5", "m6", "m7"]
    big = DelayQueue(1.0, max_messages=100, max_bytes=1000)
    for i in range(10):
        big.push(b"x" * 300, float(i), now_s=float(i))
    assert big.held_bytes <= 1000 and len(big) == 3
    with pytest.raises(InvalidField):
        DelayQueue(8.0)


def test_capture_time_is_read_from_packed_camera_and_telemetry_messages() -> None:
    header = json.dumps({"capture_unix_s": 12.5}).encode()
    assert capture_time_s(struct.pack(">I", len(header)) + header + b"\xff\xd8jpeg") == 12.5
    assert capture_time_s('{"type":"telemetry","capture_unix_s":3.25}') == 3.25
    assert capture_time_s("not json") is None and capture_time_s(b"\x00") is None


def test_viewer_delay_is_reread_at_most_every_refresh_and_reports_changes() -> None:
    now = [0.0]
    stored = [0.0]
    delay = ViewerDelay(lambda: stored[0], refresh_s=1.0, clock=lambda: now[0])
    assert delay.current() == (0.0, False)
    stored[0] = 3.0
    assert delay.current() == (0.0, False)  # not re-read yet
    now[0] = 1.5
    assert delay.current() == (3.0, True)
    now[0] = 3.0
    assert delay.current() == (3.0, False)


def test_the_delay_book_reads_every_viewers_delay_in_one_query_per_period() -> None:
    now = [0.0]
    stored: Delays = {(1, None): 3.0}
    loads = []

    def load() -> Delays:
        loads.append(now[0])
        return dict(stored)

    book = DelayBook(load, refresh_s=1.0, clock=lambda: now[0])
    assert [book.delay_of(user, "lab-1") for user in (1, 2, 1, 3)] == [3.0, 0.0, 3.0, 0.0]
    assert loads == [0.0]  # four viewers, one read
    stored[(2, None)] = 1.0
    assert book.delay_of(2, "lab-1") == 0.0  # within the period
    now[0] = 1.0
    assert (book.delay_of(2, "lab-1"), book.delay_of(1, "lab-1")) == (1.0, 3.0) and loads == [0.0, 1.0]
    stored[(1, None)] = 0.0
    book.forget()  # changed in this process: read at once
    assert book.delay_of(1, "lab-1") == 0.0 and len(loads) == 3


def test_an_open_trial_s_delay_is_on_its_robot_only_and_wins_there_over_a_tutor_s() -> None:
    delays: Delays = {(1, "course-b"): 3.0, (2, "course-b"): 1.0, (2, None): 5.0}
    assert delay_in_force_s(delays, 1, "course-b") == 3.0
    assert delay_in_force_s(delays, 1, "lab-1") == 0.0  # the trial's delay stays on the trial's robot
    assert delay_in_force_s(delays, 2, "course-b") == 1.0  # the trial's condition is what is measured
    assert delay_in_force_s(delays, 2, "lab-1") == 5.0  # a tutor's delay is on every other robot
    assert delay_in_force_s(delays, 3, "course-b") == 0.0


def test_a_failed_read_keeps_the_last_delays_and_is_not_retried_by_every_viewer() -> None:
    now = [0.0]
    answers: list[Delays | Exception] = [{(1, None): 3.0}, RuntimeError("database gone"), {(1, None): 1.0}]
    calls = []

    def load() -> Delays:
        calls.append(now[0])
        answer = answers[len(calls) - 1]
        if isinstance(answer, Exception):
            raise answer
        return answer

    book = DelayBook(load, refresh_s=1.0, clock=lambda: now[0])
    viewer = ViewerDelay(lambda: book.delay_of(1, "lab-1"), refresh_s=0.0, clock=lambda: now[0])
    assert viewer.current() == (3.0, True)
    now[0] = 1.0
    assert viewer.current() == (3.0, False)  # the read failed: the last delay holds
    assert viewer.current() == (3.0, False) and len(calls) == 2  # and no retry until the next period
    now[0] = 2.0
    assert viewer.current() == (1.0, True)


def test_many_viewers_at_once_make_one_read() -> None:
    import threading

    calls = []
    gate = threading.Event()

    def load() -> Delays:
        calls.append(1)
        gate.wait(5)
        return {(7, None): 2.0}

    book = DelayBook(load, refresh_s=60.0)
    answers: list[float] = []
    viewers = [threading.Thread(target=lambda: answers.append(book.delay_of(7, "lab-1"))) for _ in range(20)]
    for viewer in viewers:
        viewer.start()
    time.sleep(0.2)  # the others arrive while the first read is still under way
    gate.set()
    for viewer in viewers:
        viewer.join(5)
    assert answers == [2.0] * 20 and calls == [1]


def _trial(i: int, course: str, delay: float, feedback: bool, time_s: float, errors: int = 0) -> Trial:
    return Trial(id=i, user_id=1, robot_name="c", course=course, delay_s=delay, feedback=feedback,
                 status="completed", total_time_s=time_s, errors=errors)


def test_means_and_standard_errors_per_condition() -> None:
    trials = [_trial(1, "course-A", 3.0, True, 60), _trial(2, "course-A", 3.0, True, 70, 1),
              _trial(3, "course-A", 3.0, True, 80), _trial(4, "course-A", 3.0, False, 90),
              Trial(id=5, user_id=1, robot_name="c", course="course-B", delay_s=1.0, feedback=True,
                    status="abandoned", total_time_s=None, errors=0)]
    stats = summarise(trials)
    assert [(g.course, g.delay_s, g.feedback, g.n) for g in stats] == [("course-A", 3.0, True, 3),
                                                                      ("course-A", 3.0, False, 1)]
    on = stats[0]
    assert on.mean_time_s == pytest.approx(70.0)
    assert on.standard_error_s == pytest.approx(10.0 / math.sqrt(3))  # sample sd 10, n = 3
    assert on.mean_errors == pytest.approx(1 / 3)
    assert stats[1].standard_error_s is None


def test_csv_quotes_cells_that_a_spreadsheet_would_run() -> None:
    text = results_csv([(_trial(1, "course-A", 1.0, True, 42.0), "=cmd|calc"), (_trial(2, "course-B", 3.0, False, 9.5),
                                                                               "@evil")])
    lines = text.splitlines()
    assert lines[0].startswith("trial_id,username,robot,course,delay_s,feedback,commands_delayed,total_time_s,errors")
    assert "age" not in lines[0], "no participant details unless a tutor enables them"
    assert "'=cmd|calc" in lines[1] and "'@evil" in lines[2] and ",on," in lines[1] and ",off," in lines[2]
