"""The refusals of the converted modules speak the request's language: every Refused, ApiError or InvalidInput
(or an area's subclass of them, accounts' `forbidden()`, or a socket's `refuse()`; a plan's PlanError and the
StepProblem and reports its readers make) they make is given its sentence through gettext or lazy_gettext with
%(name)s placeholders, never as a bare string, an f-string, a concatenation or a choice of bare strings, which
would reach a Spanish student in English.

CONVERTED only grows: add a module once its refusals are converted (and their msgids translated in both .po files,
tests/unit/test_i18n_catalogue.py checks); never take one off. A sentence held in a variable is not checked (say
it through gettext where it is made)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MIDDLEWARE = ROOT / "middleware"

CONVERTED = (
    "middleware/validation.py",
    "middleware/api/contract.py",
    "middleware/errors.py",
    "middleware/bookings",
    "middleware/chat",
    "middleware/assessment",
    "middleware/accounts",
    "middleware/courses",
    "middleware/preferences",
    "middleware/lab/skills.py",
    "middleware/experiment/services.py",
    "middleware/experiment/routes.py",
    "middleware/teaching/tour_routes.py",
    "middleware/teaching/lesson_routes.py",
    "middleware/teaching/lesson_tests.py",
    "middleware/teaching/lesson_uploads.py",
    "middleware/teaching/authority.py",
    "middleware/teaching/targets.py",
    "middleware/teaching",
    "middleware/plans",
    "middleware/exercises",
    "middleware/recordings",
    "middleware/experiment",
    "middleware/farm",
    "middleware/access",
    "middleware/auth",
    "middleware/robots",
    "middleware/lab",
    "middleware/live",
    "middleware/realtime.py",
    "middleware/web.py",
    "middleware/extensions.py",
    "middleware",  # every module of the middleware (issue 29): a new one speaks the request's language from the start
    "middleware/lti",
)
BASES = {"Refused", "ApiError", "InvalidInput", "PlanError", "StepProblem"}  # a plan's errors reach the user too
# functions that make a Refused, or close a socket, with the sentence given; and the plan readers' reporters, which
# make a PlanError at a line and column (place_error, the parsers' report and at, the tokenizer's _bad and _report)
HELPERS = {"forbidden", "refuse", "place_error", "report", "at", "_bad", "_report"}


def _name(node: ast.expr) -> str | None:
    return node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else None


def refusal_classes() -> set[str]:
    """Refused, ApiError, InvalidInput and every class of the middleware derived from them."""
    bases: dict[str, set[str]] = {}
    for path in MIDDLEWARE.rglob("*.py"):
        source = path.read_text(encoding="utf-8")
        if "class " not in source:
            continue
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.ClassDef):
                bases.setdefault(node.name, set()).update(filter(None, map(_name, node.bases)))
    found, grown = set(BASES), True
    while grown:
        grown = False
        for name, parents in bases.items():
            if name not in found and parents & found:
                found.add(name)
                grown = True
    return found


def _is_prose(node: ast.expr) -> bool:
    """Whether node is English said outside gettext: a string or f-string with a space in its own text, or such
    strings joined (+) or chosen between (a if c else b, a or b)."""
    if isinstance(node, ast.Constant):
        return isinstance(node.value, str) and " " in node.value.strip()
    if isinstance(node, ast.JoinedStr):
        return any(isinstance(part, ast.Constant) and " " in str(part.value) for part in node.values)
    if isinstance(node, ast.BinOp):
        return _is_prose(node.left) or _is_prose(node.right)
    if isinstance(node, ast.IfExp):
        return _is_prose(node.body) or _is_prose(node.orelse)
    if isinstance(node, ast.BoolOp):
        return any(_is_prose(value) for value in node.values)
    return False


def english_refusals(source: str, classes: set[str]) -> list[tuple[int, str]]:
    """(line, text) of each refusal in source whose sentence is English outside gettext."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and _name(node.func) in classes | HELPERS:
            for argument in [*node.args, *(keyword.value for keyword in node.keywords)]:
                if _is_prose(argument):
                    found.append((argument.lineno, ast.unparse(argument)[:80]))
    return found


def _modules() -> list[Path]:
    paths = []
    for entry in CONVERTED:
        path = ROOT / entry
        paths.extend(sorted(path.rglob("*.py")) if path.is_dir() else [path])
    return sorted(set(paths))  # a module listed and inside a package listed is read once


def test_every_converted_module_says_its_refusals_through_gettext() -> None:
    classes = refusal_classes()
    assert {"BookingRefused", "ChatRefused", "TimeUp", "UploadRefused"} <= classes
    outside = [f"{path.relative_to(ROOT)}:{line}: {text}" for path in _modules()
               for line, text in english_refusals(path.read_text(encoding="utf-8"), classes)]
    assert not outside, ("Say these refusals with gettext(\"... %(name)s ...\", name=...) and translate them in "
                         "both .po files:\n" + "\n".join(outside))


@pytest.mark.parametrize(("source", "expected"), [
    ('raise Refused(404, "unknown_course", "There is no such course.", "course_id")', 1),
    ('raise BookingRefused(409, "slot_taken", f"{name} is booked then.", "starts_at")', 1),
    ('raise InvalidInput("body", "The JSON is " + kind)', 1),
    ('raise ApiError(409, "x", "Not yet." if early else "Too late.")', 1),
    ('raise forbidden("You can read only your own.")', 1),
    ('refuse(ws, CLOSE_FORBIDDEN, "forbidden_origin", "This page may not open this channel.")', 1),
    ('refuse(ws, CLOSE_NOT_FOUND, "unknown_goal", gettext("There is no goal with that id."), "goal_id")', 0),
    ('raise Refused(404, "unknown_course", gettext("There is no course %(id)s.", id=i), "course_id")', 0),
    ('raise Refused(409, "done", lazy_gettext("Already answered."))', 0),
    ('raise InvalidInput(f"{ZONE}.rects[{index}]", gettext("Four numbers."))', 0),
    ('raise Refused(400, "invalid_field", message, field)', 0),
    ('PlanError(line, column, field, f"line {line}: {message}")', 1),
    ('PlanError(0, 0, "plan", "The plan is not valid.")', 1),
    ('raise StepProblem("value", f"{kind} takes no value; got {written}.")', 1),
    ('errors.append(place_error(step.line, step.column, where, "this on has nothing in its block."))', 1),
    ('self.report(token.line, token.column, "this } closes no block; remove it.", path)', 1),
    ('raise self.at(token, path, f"{token.text} is given twice.")', 1),
    ('self._bad(number, start, written, "this text has no closing quote on its line.")', 1),
    ('PlanError(line, column, field, gettext("line %(line)s: %(problem)s", line=line, problem=message))', 0),
    ('raise StepProblem(f"{path}.negate", gettext("negate must be true or false; got %(value)s.", value=v))', 0),
    ('raise self.at(token, path, gettext("%(name)s is given twice.", name=name))', 0),
])
def test_the_check_finds_english_refusals(source: str, expected: int) -> None:
    classes = BASES | {"BookingRefused"}
    assert len(english_refusals(source, classes)) == expected
