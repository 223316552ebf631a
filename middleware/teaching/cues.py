"""A lesson's cue track: WebVTT (or SRT, converted) whose every cue body is one declarative robot command.

Pure: parse_cue_track(text, skills) -> (cues, errors). Errors carry the line number and the field, and every
error in the track is reported, not only the first. Nothing from a track is ever run: a body is JSON, checked
by middleware.teaching.command_form; STYLE and REGION blocks are refused, NOTE blocks are dropped, and the
canonical WebVTT written back contains only timings, cue ids and re-serialised commands.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.errors import written_number
from middleware.teaching.command_form import CommandInvalid, RobotCommand, SkillSchemas, parse_command
from middleware.validation import decimal_int

MAX_TRACK_CHARS = 200_000
MAX_CUES = 500
MAX_BODY_CHARS = 2_000
MAX_TIME_S = 6 * 3600.0  # a lesson video is at most six hours long
MAX_ERRORS = 50
TIMING = re.compile(
    r"^(?P<start>(?:\d{1,3}:)?\d{1,3}:\d{1,3}[.,]\d{1,3})[ \t]+-->[ \t]+"
    r"(?P<end>(?:\d{1,3}:)?\d{1,3}:\d{1,3}[.,]\d{1,3})(?P<settings>[ \t].*)?$"
)
TIMESTAMP = re.compile(r"^(?:(?P<h>\d{1,3}):)?(?P<m>\d{1,3}):(?P<s>\d{1,3})[.,](?P<ms>\d{1,3})$", re.ASCII)


@dataclass(frozen=True)
class Cue:
    """One cue: its interval [start_s, end_s), the command, and the line of its timing in the source."""

    index: int
    start_s: float
    end_s: float
    command: RobotCommand
    line: int

    @property
    def cue_id(self) -> str:
        """The id written into the WebVTT track, which the page sends back to run the cue."""
        return f"cue-{self.index}"

    def to_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        return {"id": self.cue_id, "index": self.index, "start_s": self.start_s, "end_s": self.end_s,
                "command": self.command.to_dict(), "line": self.line}


@dataclass(frozen=True)
class CueError:
    """One problem in a track: the line (1-based), the field, and what to do."""

    line: int
    field: str
    message: str

    def to_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        return {"line": self.line, "field": self.field, "message": self.message}


def parse_timestamp(text: str) -> float | None:
    """Seconds of a WebVTT/SRT timestamp (hh:mm:ss.ttt or mm:ss.ttt), or None if it is not one."""
    match = TIMESTAMP.fullmatch(text)
    if match is None:
        return None
    hours, minutes, seconds = int(match["h"] or 0), int(match["m"]), int(match["s"])
    if minutes > 59 or seconds > 59:
        return None
    return hours * 3600 + minutes * 60 + seconds + int(match["ms"].ljust(3, "0")) / 1000


def format_timestamp(seconds: float) -> str:
    """hh:mm:ss.ttt."""
    millis = round(seconds * 1000)
    hours, rest = divmod(millis, 3_600_000)
    minutes, rest = divmod(rest, 60_000)
    return f"{hours:02d}:{minutes:02d}:{rest // 1000:02d}.{rest % 1000:03d}"


def _blocks(lines: list[str], first: int) -> list[tuple[int, list[str]]]:
    """(line number of the block's first line, its lines) for every blank-line-separated block from index first."""
    blocks: list[tuple[int, list[str]]] = []
    current: list[str] = []
    start = 0
    for number, line in enumerate(lines[first:], start=first + 1):
        if line.strip():
            if not current:
                start = number
            current.append(line)
        elif current:
            blocks.append((start, current))
            current = []
    if current:
        blocks.append((start, current))
    return blocks


def parse_cue_track(text: object, skills: SkillSchemas | None) -> tuple[list[Cue], list[CueError]]:
    """The cues of a WebVTT or SRT track and every error found, each naming its line."""
    if not isinstance(text, str):
        return [], [CueError(0, "cues", gettext("The cue track must be text (WebVTT or SRT)."))]
    if len(text) > MAX_TRACK_CHARS:
        return [], [CueError(0, "cues", gettext("The cue track is longer than %(limit)s characters.",
                                                 limit=MAX_TRACK_CHARS))]
    if "\x00" in text:
        return [], [CueError(0, "cues", gettext("The cue track contains a NUL character; save it as plain UTF-8 "
                                                 "text."))]
    lines = text.lstrip("\ufeff").replace("\r\n", "\n").replace("\r", "\n").split("\n")
    first = 0
    is_vtt = bool(lines) and (lines[0] == "WEBVTT" or lines[0].startswith(("WEBVTT ", "WEBVTT\t")))
    if is_vtt:
        first = 1
        while first < len(lines) and lines[first].strip():  # header lines up to the first blank
            first += 1
    errors: list[CueError] = []
    cues: list[Cue] = []
    for start_line, block in _blocks(lines, first):
        if len(errors) >= MAX_ERRORS:
            break
        head = block[0].strip()
        if head.startswith("NOTE") and (len(head) == 4 or head[4] in " \t"):
            continue
        if head in {"STYLE", "REGION"}:
            errors.append(CueError(start_line, "cues", gettext("%(head)s blocks are not allowed in a lesson's cue "
                                                                  "track.", head=head)))
            continue
        timing_at = next((i for i, line in enumerate(block[:2]) if "-->" in line), None)
        if timing_at is None:
            if not is_vtt and decimal_int(head, 0) is not None and len(block) == 1:
                errors.append(CueError(start_line, "cues", gettext("A cue number with no timing line after it.")))
            else:
                errors.append(CueError(start_line, "cues",
                                       gettext("Expected a timing line such as 00:00:01.000 --> 00:00:04.000.")))
            continue
        line_number = start_line + timing_at
        if len(cues) >= MAX_CUES:
            errors.append(CueError(line_number, "cues", gettext("A track has at most %(limit)s cues.", limit=MAX_CUES)))
            break
        cue = _parse_cue(block[timing_at].strip(), "\n".join(block[timing_at + 1:]), line_number, len(cues) + 1,
                         skills, errors)
        if cue is None:
            continue
        if cues and cue.start_s < cues[-1].start_s:
            errors.append(CueError(line_number, "start", gettext("Cues must be in order of their start times.")))
            continue
        if cues and cue.start_s < cues[-1].end_s:
            errors.append(CueError(line_number, "start", gettext(
                "This cue starts before the cue on line %(line)s ends; cues must not overlap (one command at a "
                "time).", line=cues[-1].line)))
            continue
        cues.append(cue)
    if not errors and not cues:
        errors.append(CueError(0, "cues", gettext("The cue track has no cues.")))
    return cues, errors


def _parse_cue(timing: str, body: str, line: int, index: int, skills: SkillSchemas | None,
               errors: list[CueError]) -> Cue | None:
    match = TIMING.fullmatch(timing)
    if match is None:
        errors.append(CueError(line, "timing", gettext("Expected a timing line such as 00:00:01.000 --> "
                                                       "00:00:04.000.")))
        return None
    start_s, end_s = parse_timestamp(match["start"]), parse_timestamp(match["end"])
    if start_s is None or end_s is None:
        errors.append(CueError(line, "timing", gettext("A timestamp has minutes or seconds above 59.")))
        return None
    if start_s > MAX_TIME_S or end_s > MAX_TIME_S:
        errors.append(CueError(line, "timing", gettext("Cue times must be within %(hours)s hours.",
                                                       hours=written_number(MAX_TIME_S / 3600, "g"))))
        return None
    if end_s <= start_s:
        errors.append(CueError(line, "end", gettext("A cue must end after it starts.")))
        return None
    if not body.strip():
        errors.append(CueError(line + 1, "command", gettext("A cue needs a command as its body, e.g. {\"stop\": "
                                                               "true}.")))
        return None
    if len(body) > MAX_BODY_CHARS:
        errors.append(CueError(line + 1, "command", gettext("A cue body has at most %(limit)s characters.",
                                                               limit=MAX_BODY_CHARS)))
        return None
    try:
        value = json.loads(body)
    except ValueError:
        errors.append(CueError(line + 1, "command", gettext('A cue body must be one JSON command, e.g. '
                                                            '{"skill": "go_to_goal", "parameters": {"goal_x_m": '
                                                            '1}}.')))
        return None
    try:
        command = parse_command(value, skills, sounds=True)
    except CommandInvalid as invalid:
        errors.append(CueError(line + 1, invalid.field, invalid.message))
        return None
    return Cue(index, start_s, end_s, command, line)


def _safe_json(value: object) -> str:
    # No '<', '>' or '&' in the track, so a body can never read as markup or close a cue ("-->").
    text = json.dumps(value, separators=(",", ":"), sort_keys=True)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def to_webvtt(cues: list[Cue]) -> str:
    """The canonical WebVTT of checked cues: ids cue-1.., timings, one JSON command per body."""
    parts = ["WEBVTT", ""]
    for cue in cues:
        parts += [cue.cue_id, f"{format_timestamp(cue.start_s)} --> {format_timestamp(cue.end_s)}",
                  _safe_json(cue.command.to_dict()), ""]
    return "\n".join(parts)
