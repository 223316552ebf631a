"""The edge's parsing of numbers and text, at the functions every form, API and WebSocket message goes through:
only ASCII digits are a number ('²' and '٣' pass str.isdigit() or \\d), thousands of digits are refused before
int() sees them, and text that cannot be stored is refused naming its line and column."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from middleware.auth.schemas import InvalidField
from middleware.validation import InvalidInput, decimal_int, parse_message, unstorable_place, whole_number

NOT_ASCII_NUMBERS = ("²", "¹²³", "٣", "٠٧", "７", "1²", "1" * 5000, "9" * 20, "", " ", "1e3", "0x10", "1_000", "१")


@pytest.mark.parametrize("text", NOT_ASCII_NUMBERS)
def test_only_a_bounded_run_of_ascii_digits_is_a_whole_number(text: str) -> None:
    assert decimal_int(text) is None
    with pytest.raises(InvalidInput) as refused:
        whole_number(text, "count", 1, 50)
    assert refused.value.field == "count" and "from 1 to 50" in refused.value.message


@given(st.integers(-(2**63), 2**63 - 1))
def test_every_int64_written_in_ascii_reads_back(number: int) -> None:
    assert decimal_int(str(number)) == number == decimal_int(f" {number} ")


@pytest.mark.parametrize("text", ("٣", "²", "1" * 5000, "-1", "+3"))
def test_a_course_setting_takes_ascii_digits_only(text: str) -> None:
    from middleware.courses.schemas import clean_whole

    with pytest.raises(InvalidField):
        clean_whole(text, "max_attempts", (1, 10), "attempts")
    assert clean_whole(" 7 ", "max_attempts", (1, 10), "attempts") == 7


def test_a_robot_address_and_a_cue_time_take_ascii_digits_only() -> None:
    from middleware.accounts.schemas import clean_robot_address
    from middleware.teaching.cues import parse_timestamp

    with pytest.raises(InvalidField):
        clean_robot_address("robot-host:٥٠٠٥١")
    assert clean_robot_address("robot-host:50051") == "robot-host:50051"
    assert parse_timestamp("٠٠:٠١.٠٠٠") is None and parse_timestamp("00:01.000") == 1.0


@pytest.mark.parametrize(("text", "place"), [
    ("a\x00", "column 2: a NUL"), ("ok\nok\n  \ud800", "line 3, column 3: a lone surrogate"), ("fine", ""),
])
def test_the_place_of_an_unstorable_character_is_named(text: str, place: str) -> None:
    assert unstorable_place(text) == place


@given(st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=8),
                 st.lists(st.text(max_size=3), max_size=2), st.dictionaries(st.text(max_size=3), st.integers(),
                                                                             max_size=2)))
def test_a_message_type_that_is_not_one_of_the_channels_strings_names_type(kind: object) -> None:
    import json

    if kind in ("say", "delete"):
        return
    with pytest.raises(InvalidInput) as refused:
        parse_message(json.dumps({"type": kind}), ("say", "delete"), 4096)
    assert str(refused.value.field).split(".")[0].split("[")[0] in {"type", "message"}
