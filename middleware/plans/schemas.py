"""What the plans API accepts, checked at the edge: names, text, course ids, run targets, export formats and files.

The plan itself is checked by the language (middleware.plans.language); this module checks everything around it
and turns a file's bytes into a plan's text or JSON document, naming the line when the file is not JSON.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import PurePath

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.auth.schemas import InvalidField
from middleware.plans.language import MAX_TEXT_BYTES, PlanError, PlanInvalid, is_plan_name
from middleware.validation import InvalidInput, decimal_int, loads_checked, unstorable, unstorable_place

MAX_JSON_FILE_BYTES = 4 * MAX_TEXT_BYTES  # the canonical JSON is wordier than the text it comes from
EXPORT_FORMATS = ("json", "txt")
IMPORT_SUFFIXES = {".json": "json", ".txt": "txt", ".plan": "txt"}


def plan_name(value: object, field: str = "name") -> str:
    """A plan's name, or a 400 naming field."""
    if not is_plan_name(value):
        raise InvalidField(field, gettext("A plan's name is 1 to 64 letters, digits, - and _ (no spaces)."))
    assert isinstance(value, str)
    return value


def plan_text(value: object, field: str = "text") -> str:
    """A plan's text as written (the language checks what it says), or a 400 naming field."""
    if not isinstance(value, str):
        raise InvalidField(field, gettext("text must be the plan's text, one command a line."))
    if len(value.encode("utf-8", "surrogatepass")) > MAX_TEXT_BYTES:
        raise InvalidField(field, gettext("A plan's text is at most %(limit)s bytes.", limit=MAX_TEXT_BYTES))
    if unstorable(value):
        raise InvalidField(field, gettext("The text holds a character that cannot be stored (%(place)s); remove it.",
                                          place=unstorable_place(value)))
    return value


def optional_course_id(value: object, field: str = "course_id") -> int | None:
    """A course's id or null (shared with no course), or a 400 naming field."""
    if value is None:
        return None
    number = decimal_int(value, 1, 2**31 - 1)
    if number is None or isinstance(value, str):
        raise InvalidField(field, gettext("course_id must be a course's id (a whole number) or null."))
    return number


def optional_version(value: object, field: str = "version") -> int | None:
    """A version number (from a query string or JSON) or None for the latest, or a 400 naming field."""
    if value is None or value == "":
        return None
    number = decimal_int(value, 1, 2**31 - 1)
    if number is None:
        raise InvalidField(field, gettext("version must be a whole number from 1."))
    return number


def export_format(value: object) -> str:
    """json (the canonical form, the default) or txt."""
    if value is None or value == "":
        return "json"
    if value not in EXPORT_FORMATS:
        raise InvalidField("format", gettext("format must be json or txt."))
    assert isinstance(value, str)
    return value


def run_target(value: object, field: str = "target") -> str:
    """Where a plan runs: "practice" (the user's practice robot) or a lab robot's name."""
    if not isinstance(value, str) or not 0 < len(value) <= 64 or unstorable(value):
        raise InvalidField(field, gettext('%(field)s must be "practice" or a lab robot\'s name.', field=field))
    return value


def flag(value: object, field: str) -> bool:
    """A JSON boolean (missing is false), or a 400 naming field."""
    if value is None:
        return False
    if not isinstance(value, bool):
        raise InvalidField(field, gettext("%(field)s must be true or false.", field=field))
    return value


@dataclass(frozen=True)
class PlanFile:
    """An imported file: the name it suggests and its content, either text or a decoded JSON document."""

    suggested_name: str
    kind: str  # "json" or "txt"
    text: str | None
    document: object


def read_plan_file(filename: object, content: bytes) -> PlanFile:
    """An uploaded plan file (.json in the canonical form, or .txt/.plan text); 400 naming "file" otherwise, with
    the line when the JSON does not parse."""
    if not isinstance(filename, str) or not filename:
        raise InvalidField("file", gettext("Choose a plan file (.json or .txt) to import."))
    path = PurePath(filename.replace("\\", "/"))
    kind = IMPORT_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise InvalidField("file", gettext("A plan file ends in .json (the exported form) or .txt (the plan's text)."))
    limit = MAX_JSON_FILE_BYTES if kind == "json" else MAX_TEXT_BYTES
    if len(content) > limit:
        raise InvalidField("file", gettext("The file is larger than %(kib)s KiB; a plan file is at most that.",
                                           kib=limit // 1024))
    try:
        decoded = content.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = content[:error.start].count(b"\n") + 1
        raise InvalidField("file", gettext("line %(line)s: the file is not UTF-8 text.", line=line)) from None
    suggested = "".join(c if c.isascii() and (c.isalnum() or c in "-_") else "_" for c in path.stem)[:64] or "plan"
    if kind == "txt":
        return PlanFile(suggested, kind, plan_text(decoded, "file"), None)
    try:
        document = loads_checked(decoded)
    except InvalidInput as refused:
        raise InvalidField("file", refused.message) from None
    except ValueError as error:
        line, column = getattr(error, "lineno", 0), getattr(error, "colno", 0)
        reason = getattr(error, "msg", "not JSON")  # the JSON parser's own words
        raise PlanInvalid([PlanError(line, column, "file", gettext(
            "line %(line)s, column %(column)s: the file is not JSON (%(reason)s).", line=line, column=column,
            reason=reason))]) from None
    return PlanFile(suggested, kind, None, document)
