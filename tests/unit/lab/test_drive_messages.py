"""Drive messages from browsers: hostile ones get an error naming the field; valid ones parse exactly."""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from middleware.auth.schemas import InvalidField
from middleware.lab.schemas import DriveLimits, DriveRequest, parse_drive_message

LIMITS = DriveLimits(max_linear_mps=0.5, max_angular_radps=1.5)


def drive(**fields: object) -> str:
    return json.dumps({"type": "drive", "sequence": 1, "linear_mps": 0.1, "angular_radps": 0.0, **fields})


def test_a_valid_drive_and_a_stop_parse() -> None:
    assert parse_drive_message(drive(linear_mps=0.5, angular_radps=-1.5), LIMITS, 0) == DriveRequest(1, 0.5, -1.5)
    assert parse_drive_message('{"type":"stop","sequence":7}', LIMITS, 6) == DriveRequest(7, 0.0, 0.0)


@pytest.mark.parametrize(
    ("raw", "field"),
    [
        (None, "message"),
        (b"\x00\x01", "message"),
        ("not json", "message"),
        ("[1, 2]", "message"),
        ("x" * 5000, "message"),
        ('{"sequence": 1}', "type"),
        ('{"type": "launch", "sequence": 1}', "type"),
        (drive(sequence=0), "sequence"),
        (drive(sequence=-3), "sequence"),
        (drive(sequence=1.5), "sequence"),
        (drive(sequence=True), "sequence"),
        (drive(sequence="1"), "sequence"),
        (drive(sequence=2**60), "sequence"),
        (drive(linear_mps="fast"), "linear_mps"),
        (drive(linear_mps=None), "linear_mps"),
        (drive(linear_mps=True), "linear_mps"),
        (drive(linear_mps=1e300), "linear_mps"),
        (drive(linear_mps=0.51), "linear_mps"),
        (drive(angular_radps=-99), "angular_radps"),
        ('{"type":"drive","sequence":1,"linear_mps":NaN,"angular_radps":0}', "linear_mps"),
        ('{"type":"drive","sequence":1,"linear_mps":0,"angular_radps":Infinity}', "angular_radps"),
        ('{"type":"drive","sequence":1,"angular_radps":0}', "linear_mps"),
    ],
)
def test_hostile_drive_messages_are_refused_naming_the_field(raw: object, field: str) -> None:
    with pytest.raises(InvalidField) as refused:
        parse_drive_message(raw, LIMITS, 0)
    assert refused.value.field == field
    assert refused.value.message


def test_a_sequence_that_does_not_increase_is_refused() -> None:
    with pytest.raises(InvalidField, match="greater than the previous") as refused:
        parse_drive_message(drive(sequence=5), LIMITS, 5)
    assert refused.value.field == "sequence"


@given(linear=st.floats(allow_nan=True, allow_infinity=True), angular=st.floats(allow_nan=True, allow_infinity=True))
def test_any_accepted_command_is_finite_and_within_the_limits(linear: float, angular: float) -> None:
    raw = json.dumps({"type": "drive", "sequence": 1, "linear_mps": linear, "angular_radps": angular})
    try:
        command = parse_drive_message(raw, LIMITS, 0)
    except InvalidField:
        return
    assert math.isfinite(command.linear_mps) and abs(command.linear_mps) <= LIMITS.max_linear_mps
    assert math.isfinite(command.angular_radps) and abs(command.angular_radps) <= LIMITS.max_angular_radps
