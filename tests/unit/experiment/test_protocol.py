"""The thesis' protocol as rules: a Williams design counterbalances the five conditions, the comparisons are the
thesis' figures, and details go into an export only with consent and a tutor's leave."""

from __future__ import annotations

from collections import Counter
from datetime import UTC, datetime, timedelta

import pytest

from middleware.experiment import protocol
from middleware.experiment.services import GroupStats, compare, results_csv
from middleware.models.experiment import Participant, Trial


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_a_williams_design_puts_each_condition_first_and_after_each_other_equally_often(n: int) -> None:
    rows = protocol.williams_orders(n)
    assert all(sorted(row) == list(range(n)) for row in rows)
    positions = Counter((position, c) for row in rows for position, c in enumerate(row))
    assert len(set(positions.values())) == 1, "each condition in each position equally often"
    pairs = Counter((a, b) for row in rows for a, b in zip(row, row[1:], strict=False))
    assert len(pairs) == n * (n - 1) and len(set(pairs.values())) == 1, "each ordered pair equally often"


def test_the_five_conditions_are_the_control_and_both_delays_with_and_without_the_preview() -> None:
    assert protocol.CONDITIONS_PER_COURSE == ((0.0, False), (1.0, True), (1.0, False), (3.0, True), (3.0, False))
    assert len(protocol.ORDERS) == 10  # odd: the rows and their mirrors


def test_the_comparisons_are_the_time_the_preview_saves_and_each_mean_against_the_control() -> None:
    stats = [GroupStats("course-A", 0.0, False, 2, 50.0, 1.0, 0), GroupStats("course-A", 3.0, True, 2, 60.0, 2.0, 0),
             GroupStats("course-A", 3.0, False, 2, 80.0, 2.0, 0), GroupStats("course-B", 1.0, False, 1, 90.0, None, 0)]
    by_key = {(c.course, c.delay_s): c for c in compare(stats)}
    a3 = by_key[("course-A", 3.0)]
    assert a3.preview_saves == pytest.approx(0.25)  # the thesis: 80 s without, 60 s with = 25 % less
    assert (a3.on_vs_control, a3.off_vs_control) == (pytest.approx(1.2), pytest.approx(1.6))
    b1 = by_key[("course-B", 1.0)]
    assert b1.preview_saves is None and b1.off_vs_control is None, "no control and no preview trial yet"
    assert ("course-A", 1.0) not in by_key


def test_the_learning_period_counts_down_from_its_start_and_none_set_means_ready() -> None:
    now = datetime(2026, 11, 28, 10, 0, tzinfo=UTC)
    row = Participant(user_id=1, consent=False, learning_started_at=now - timedelta(seconds=100))
    assert protocol.learning_left_s(row, protocol.Protocol(learning_s=300), now) == pytest.approx(200)
    assert protocol.learning_left_s(row, protocol.Protocol(learning_s=60), now) == 0
    assert protocol.learning_left_s(Participant(user_id=2), protocol.Protocol(learning_s=300), now) is None
    assert protocol.learning_left_s(None, protocol.Protocol(learning_s=0), now) == 0


def test_an_export_carries_details_only_for_the_participants_handed_in() -> None:
    trial = Trial(id=1, user_id=7, robot_name="c", course="course-A", delay_s=0.0, feedback=False,
                  status="completed", total_time_s=40.0, errors=0, commands_delayed=False)
    person = Participant(user_id=7, consent=True, age=23, location="remote", games_experience="some",
                         robots_experience="none")
    header, line = results_csv([(trial, "ana")], {7: person}).splitlines()
    assert header.endswith("age,location,games_experience,robots_experience")
    assert line.endswith("23,remote,some,none")
    assert "age" not in results_csv([(trial, "ana")], {}).splitlines()[0]
