"""A cue may play a sound with a caption (the 2022 paper's third coordination point): checked like any command, every
error naming its line and field; the robot stands still; tours take no sounds."""

from __future__ import annotations

import pytest

from middleware.teaching.command_form import CommandInvalid, RobotCommand, parse_command
from middleware.teaching.cues import parse_cue_track, to_webvtt

SOUND = '{"sound": {"frequency_hz": 660, "duration_s": 0.8, "caption": "The robot beeps <twice>"}}'


def test_a_sound_cue_keeps_its_tone_and_caption_and_moves_nothing() -> None:
    cues, errors = parse_cue_track(f"WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{SOUND}\n", None)
    assert errors == []
    command = cues[0].command
    assert command.to_dict() == {"sound": {"frequency_hz": 660.0, "duration_s": 0.8,
                                           "caption": "The robot beeps <twice>"}}
    assert command.motion() == RobotCommand("stop")
    track = to_webvtt(cues)
    assert "<twice>" not in track and [c.command for c in parse_cue_track(track, None)[0]] == [command]


@pytest.mark.parametrize("sound, field", [
    ('{"frequency_hz": 660, "duration_s": 0.8}', "sound.caption"),
    ('{"frequency_hz": 660, "duration_s": 0.8, "caption": "   "}', "sound.caption"),
    ('{"caption": "' + "x" * 121 + '"}', "sound.caption"),
    ('{"frequency_hz": 20, "caption": "low"}', "sound.frequency_hz"),
    ('{"frequency_hz": 1e400, "caption": "inf"}', "sound.frequency_hz"),
    ('{"duration_s": 60, "caption": "long"}', "sound.duration_s"),
    ('{"duration_s": true, "caption": "bool"}', "sound.duration_s"),
    ('{"volume": 11, "caption": "loud"}', "sound"),
    ('"beep"', "sound"),
])
def test_a_sound_that_cannot_be_played_or_read_is_refused_naming_line_and_field(sound, field) -> None:
    _cues, errors = parse_cue_track(f"WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{{\"sound\": {sound}}}\n", None)
    assert [(e.line, e.field) for e in errors] == [(4, field)]


def test_a_tour_step_plays_no_sound() -> None:
    with pytest.raises(CommandInvalid) as refused:
        parse_command({"sound": {"caption": "beep"}}, None)
    assert refused.value.field == "sound"
