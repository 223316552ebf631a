"""The robot's pose log: a sample per period, read back between two wall-clock times, refusing a bad range."""

from __future__ import annotations

import math
import random
from itertools import pairwise

import pytest

from skill_server.errors import InvalidParameter
from skill_server.sim.geometry import Pose2D
from skill_server.sim.odometry import OdometryReading
from skill_server.sim.pacing import SimTimePacer
from skill_server.sim.pose_log import PoseLog
from skill_server.sim.snapshots import RobotSnapshot


def _snapshot(at: float, x: float) -> RobotSnapshot:
    return RobotSnapshot(tick=0, sim_time_s=at, capture_unix_s=at, last_applied_sequence=0,
                         odometry=OdometryReading(Pose2D(x + 0.01, 0.0, 0.0), 0.0, 0.0),
                         ground_truth=Pose2D(x, 0.0, 0.0), sonar_ranges_m=(), laser_ranges_m=(),
                         deadman_stopped=False, commanded_linear_mps=0.0, commanded_angular_radps=0.0)


def test_one_sample_a_period_is_kept_and_read_back_between_two_times() -> None:
    log = PoseLog(rate_hz=5.0, keep_s=10.0)
    for tick in range(0, 600):  # 10 s of a 60 Hz loop
        log.note(_snapshot(1000.0 + tick / 60, tick / 600))
    samples, oldest = log.between(1002.0, 1004.0)
    assert oldest == 1000.0
    assert 9 <= len(samples) <= 11 and all(1002.0 <= s[0] <= 1004.0 for s in samples)
    assert samples[0][4] == pytest.approx(samples[0][1] + 0.01)  # odometry beside ground truth
    for _ in range(100):  # past keep_s the oldest go
        log.note(_snapshot(1000.0 + 60.0 + _ / 5, 0.0))
    assert log.between(0.0, 2000.0)[1] > 1000.0


@pytest.mark.parametrize(("start", "end"), [(5.0, 1.0), (math.nan, 1.0), (1.0, math.nan)])
def test_a_range_that_is_no_range_is_refused_naming_the_field(start: float, end: float) -> None:
    with pytest.raises(InvalidParameter) as refused:
        PoseLog().between(start, end)
    assert refused.value.field == "from_unix_s"


def test_a_loop_whose_ticks_come_unevenly_keeps_the_log_s_rate_as_the_telemetry_stream_does() -> None:
    """A 40 Hz loop on the wall clock: each tick a few ms early or late. Sampling 'a period after the last sample'
    skipped to the tick after whenever the eighth came a hair early (4.4 Hz, so a graded run held fewer samples than
    the recorder's 5 Hz stream); the log keeps the rate on average, as SimTimePacer does for the stream."""
    rng = random.Random(7)
    log, stream, streamed = PoseLog(rate_hz=5.0, keep_s=60.0), SimTimePacer(1 / 5.0), 0
    for tick in range(400):  # 10 s
        at = 1000.0 + tick * 0.025 + rng.uniform(-0.004, 0.004)
        log.note(_snapshot(at, 0.0))
        streamed += stream.due(at)
    kept = len(log.between(0.0, 2000.0)[0])
    assert kept >= streamed - 1 and kept >= 49, (kept, streamed)
    gaps = [b[0] - a[0] for a, b in pairwise(log.between(0.0, 2000.0)[0])]
    assert max(gaps) < 0.2 + 0.025 + 0.01 and min(gaps) > 0.2 - 0.025 - 0.01
