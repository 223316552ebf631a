"""The low-level commands request at the edge: shape, numbers and the permission check, before any robot is asked."""

from __future__ import annotations

import math

import pytest

from middleware.access.limits import LIMIT_FIELDS, check_permitted, parse_limits_request
from middleware.errors import ApiError


def test_zero_and_absent_values_keep_the_robot_s() -> None:
    assert parse_limits_request({"max_linear_mps": 0.3, "max_angular_radps": 0, "watchdog_s": None}) == {
        "max_linear_mps": 0.3}
    assert parse_limits_request({"watchdog_s": 2}) == {"watchdog_s": 2.0}


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ("0.3", "body"), ([], "body"), ({}, "body"), ({"max_linear_mps": 0}, "body"),
        ({"max_linear_mps": math.nan}, "max_linear_mps"), ({"max_angular_radps": -math.inf}, "max_angular_radps"),
        ({"watchdog_s": -1}, "watchdog_s"), ({"watchdog_s": False}, "watchdog_s"), ({"watchdog_s": "1"}, "watchdog_s"),
        ({"watchdog_s": 10**400}, "watchdog_s"), ({"speed": 1}, "speed"), ({"x" * 500: 1}, "x" * 64),
    ],
)
def test_a_malformed_request_is_400_naming_the_field(body: object, field: str) -> None:
    with pytest.raises(ApiError) as refused:
        parse_limits_request(body)
    assert (refused.value.status, refused.value.code, refused.value.field) == (400, "invalid_field", field)


def test_a_setting_the_course_does_not_allow_is_403_naming_it() -> None:
    check_permitted({"max_linear_mps": 0.2}, LIMIT_FIELDS[:2])
    with pytest.raises(ApiError) as refused:
        check_permitted({"max_linear_mps": 0.2, "watchdog_s": 1.0}, LIMIT_FIELDS[:2])
    assert (refused.value.status, refused.value.code, refused.value.field) == (403, "not_permitted", "watchdog_s")
