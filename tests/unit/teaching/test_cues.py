"""Cue tracks: WebVTT and SRT parsing, and a table of hostile inputs, each refused with its line and field."""

from __future__ import annotations

import pytest

from middleware.teaching.cues import MAX_CUES, parse_cue_track, to_webvtt

SKILLS = {
    "go_to_goal": [
        {"name": "goal_x_m", "type": "double", "minimum": -50.0, "maximum": 50.0, "unit": "m", "choices": []},
        {"name": "goal_y_m", "type": "double", "minimum": -50.0, "maximum": 50.0, "unit": "m", "choices": []},
    ],
    "wall_following": [{"name": "side", "type": "enum", "minimum": 0, "maximum": 0, "choices": ["left", "right"]}],
}
GOOD = """WEBVTT

intro
00:00:01.000 --> 00:00:04.500
{"drive": {"linear_mps": 0.2, "angular_radps": 0}}

NOTE a comment is dropped

00:05.000 --> 00:09.000 align:start
{"skill": "go_to_goal", "parameters": {"goal_x_m": 1.5, "goal_y_m": -0.5}}

00:00:10.000 --> 00:00:11.000
{"stop": true}
"""


def test_a_webvtt_track_gives_its_cues_in_order() -> None:
    cues, errors = parse_cue_track(GOOD, SKILLS)
    assert errors == []
    assert [(c.start_s, c.end_s, c.command.kind) for c in cues] == [(1.0, 4.5, "drive"), (5.0, 9.0, "skill"),
                                                                     (10.0, 11.0, "stop")]
    assert cues[1].command.to_dict() == {"skill": "go_to_goal", "parameters": {"goal_x_m": 1.5, "goal_y_m": -0.5}}


def test_srt_is_accepted_and_converted_to_webvtt() -> None:
    srt = "1\r\n00:00:01,000 --> 00:00:02,000\r\n{\"stop\": true}\r\n\r\n2\r\n00:00:03,000 --> 00:00:04,250\r\n" \
          "{\"drive\": {\"linear_mps\": 0.1}}\r\n"
    cues, errors = parse_cue_track(srt, SKILLS)
    assert errors == []
    vtt = to_webvtt(cues)
    assert vtt.startswith("WEBVTT\n\ncue-1\n00:00:01.000 --> 00:00:02.000\n")
    assert "00:00:03.000 --> 00:00:04.250" in vtt
    again, errors = parse_cue_track(vtt, SKILLS)
    assert errors == [] and [c.command for c in again] == [c.command for c in cues]


HOSTILE = [
    ("script body", "WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n<script>alert(1)</script>\n", 4, "command"),
    ("html body", "WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n<b onclick=x>go</b>\n", 4, "command"),
    ("js in json string", 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"skill": "javascript:alert(1)"}\n', 4, "skill"),
    ("unknown skill", 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"skill": "self_destruct"}\n', 4, "skill"),
    ("unknown parameter", 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"skill": "go_to_goal", "parameters": '
                          '{"warp": 9}}\n', 4, "parameters.warp"),
    ("out of range", 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"skill": "go_to_goal", "parameters": '
                     '{"goal_x_m": 1e9}}\n', 4, "parameters.goal_x_m"),
    ("nan", 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"drive": {"linear_mps": NaN}}\n', 4, "drive.linear_mps"),
    ("too fast", 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"drive": {"linear_mps": 5}}\n', 4, "drive.linear_mps"),
    ("bad enum", 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"skill": "wall_following", "parameters": '
                 '{"side": "up"}}\n', 4, "parameters.side"),
    ("two commands", 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"stop": true, "drive": {}}\n', 4, "command"),
    ("extra key", 'WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"stop": true, "eval": "x"}\n', 4, "eval"),
    ("huge time", "WEBVTT\n\n999:00:00.000 --> 999:00:01.000\n{\"stop\": true}\n", 3, "timing"),
    ("minutes over 59", "WEBVTT\n\n00:99:00.000 --> 00:99:01.000\n{\"stop\": true}\n", 3, "timing"),
    ("ends before it starts", "WEBVTT\n\n00:00:05.000 --> 00:00:01.000\n{\"stop\": true}\n", 3, "end"),
    ("overlapping", "WEBVTT\n\n00:00:01.000 --> 00:00:05.000\n{\"stop\": true}\n\n00:00:04.000 --> 00:00:06.000\n"
                    "{\"stop\": true}\n", 6, "start"),
    ("out of order", "WEBVTT\n\n00:00:05.000 --> 00:00:06.000\n{\"stop\": true}\n\n00:00:01.000 --> 00:00:02.000\n"
                     "{\"stop\": true}\n", 6, "start"),
    ("style block", "WEBVTT\n\nSTYLE\n::cue { color: red }\n\n00:00:01.000 --> 00:00:02.000\n{\"stop\": true}\n",
     3, "cues"),
    ("no body", "WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n", 4, "command"),
    ("garbage timing", "WEBVTT\n\n1 --> 2\n{\"stop\": true}\n", 3, "timing"),
]


@pytest.mark.parametrize(("name", "track", "line", "field"), HOSTILE, ids=[h[0] for h in HOSTILE])
def test_hostile_cue_tracks_are_refused_with_line_and_field(name: str, track: str, line: int, field: str) -> None:
    cues, errors = parse_cue_track(track, SKILLS)
    assert errors, name
    assert (errors[0].line, errors[0].field) == (line, field), errors
    assert all(e.message for e in errors)


@pytest.mark.parametrize("value", [None, 42, b"WEBVTT", "x" * 300_000, "WEBVTT\n\n\x00", "", "WEBVTT\n"])
def test_non_tracks_are_refused(value: object) -> None:
    cues, errors = parse_cue_track(value, SKILLS)
    assert cues == [] and errors and errors[0].field == "cues"


def test_every_error_is_reported_not_only_the_first() -> None:
    track = ("WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n<i>x</i>\n\n"
             "00:00:03.000 --> 00:00:04.000\n{\"skill\": \"nope\"}\n")
    _, errors = parse_cue_track(track, SKILLS)
    assert [(e.line, e.field) for e in errors] == [(4, "command"), (7, "skill")]


def test_too_many_cues_are_refused() -> None:
    blocks = [f"00:{i // 60 % 60:02d}:{i % 60:02d}.000 --> 00:{i // 60 % 60:02d}:{i % 60:02d}.500\n{{\"stop\": true}}"
              for i in range(MAX_CUES + 1)]
    _, errors = parse_cue_track("WEBVTT\n\n" + "\n\n".join(blocks), SKILLS)
    assert errors and "at most" in errors[-1].message


def test_the_canonical_track_cannot_carry_markup() -> None:
    cues, errors = parse_cue_track('WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"skill": "go_to_goal", "parameters": '
                                   '{"goal_x_m": 1}}\n', None)
    assert not errors
    cues2, _ = parse_cue_track('WEBVTT\n\n00:00:01.000 --> 00:00:02.000\n{"skill": "x", "parameters": {"label": '
                               '"</c><script>-->"}}\n', None)
    vtt = to_webvtt(cues2)
    assert "<" not in vtt.split("\n", 1)[1] and "-->" not in vtt.split("\n")[4]
