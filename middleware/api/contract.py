"""A JSON route's contract, declared once on the route: what its body and query may hold, what it answers.

`@described(...)` goes right above a view's `def` (under `@login_required`, so a visitor not logged in hears 401
before any body is read). The same declaration

- checks the request before the view runs: the JSON body against `body` (a JSON Schema), a multipart form's
  fields against `form`, and the query string against `query`; a value outside it is a 400 `invalid_field` naming
  the field as the edge names it (`steps[0].text`), with a sentence saying what is allowed;
- is what `middleware/api/document.py` turns into the OpenAPI 3.1 document: parameters, request body, each
  answer's shape, and the refusals (`ERROR`, the shape of `errors.Refused`) with their statuses.

A view keeps its own rules (a course the user teaches, a plan the language accepts): the contract checks the shape,
the view the meaning. Schemas here are plain JSON Schema (2020-12) dicts built with the helpers below.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

from flask import request
from flask_babel import gettext  # type: ignore[import-untyped]
from jsonschema import Draft202012Validator  # type: ignore[import-untyped]
from jsonschema.exceptions import ValidationError  # type: ignore[import-untyped]

from middleware.errors import written_number
from middleware.i18n import N_
from middleware.validation import InvalidInput, decimal_int

Schema = dict[str, Any]
F = TypeVar("F", bound=Callable[..., Any])

ERROR: Schema = {
    "type": "object", "required": ["error"],
    "properties": {"error": {
        "type": "object", "required": ["code", "message", "field"],
        "properties": {"code": {"type": "string", "description": "stable, for programs (invalid_field, busy, ...)"},
                       "message": {"type": "string", "description": "a sentence saying what to do"},
                       "field": {"type": ["string", "null"], "description": "the input at fault, if one is"}}}},
}
# Statuses every logged-in JSON route may answer: bad input, not logged in, not allowed, nothing there.
COMMON_REFUSALS = (400, 401, 403, 404)
MEDIA_JSON = "application/json"
ATTRIBUTE = "__api_operation__"


# --- schema helpers: short to write on a route, plain JSON Schema underneath ---------------------------------------


def text(max_length: int | None = None, min_length: int = 0, **extra: Any) -> Schema:
    """A string of at most max_length characters."""
    schema: Schema = {"type": "string", **extra}
    if min_length:
        schema["minLength"] = min_length
    if max_length is not None:
        schema["maxLength"] = max_length
    return schema


def whole(minimum: int | None = None, maximum: int | None = None, **extra: Any) -> Schema:
    """A whole number within [minimum, maximum]."""
    schema: Schema = {"type": "integer", **extra}
    if minimum is not None:
        schema["minimum"] = minimum
    if maximum is not None:
        schema["maximum"] = maximum
    return schema


def number(minimum: float | None = None, maximum: float | None = None, **extra: Any) -> Schema:
    """A finite number within [minimum, maximum]."""
    schema: Schema = {"type": "number", **extra}
    if minimum is not None:
        schema["minimum"] = minimum
    if maximum is not None:
        schema["maximum"] = maximum
    return schema


def one_of(*values: Any, **extra: Any) -> Schema:
    """One of values."""
    return {"enum": list(values), **extra}


def nullable(schema: Schema) -> Schema:
    """schema, or null."""
    return {"anyOf": [schema, {"type": "null"}]}


def array(items: Schema | None = None, max_items: int | None = None, **extra: Any) -> Schema:
    """A list of items."""
    schema: Schema = {"type": "array", **extra}
    if items is not None:
        schema["items"] = items
    if max_items is not None:
        schema["maxItems"] = max_items
    return schema


def obj(required: tuple[str, ...] | list[str] = (), *, description: str | None = None,
        **properties: Schema) -> Schema:
    """A JSON object with properties (others allowed: a client may send more than a view reads)."""
    schema: Schema = {"type": "object", "properties": properties}
    if description:
        schema["description"] = description
    if required:
        schema["required"] = list(required)
    return schema


def obj_of(required: tuple[str, ...] | list[str], properties: dict[str, Schema],
           description: str | None = None) -> Schema:
    """obj() for properties named as Python's keywords ("from"), which cannot be passed by name."""
    return obj(required, description=description) | {"properties": properties}


def about(description: str) -> Schema:
    """A field the view reads and checks itself (several forms accepted): documented, its shape not fixed here."""
    return {"description": description}


ANY: Schema = {}
BOOLEAN: Schema = {"type": "boolean"}
ID: Schema = whole(1, 2**31 - 1)
OBJECT: Schema = {"type": "object"}
STRING: Schema = {"type": "string"}
TIME: Schema = {"type": "string", "format": "date-time"}
OK: Schema = obj(("ok",), ok=BOOLEAN)


# --- the declaration ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Answer:
    """One documented answer: its media type and the shape of its body."""

    schema: Schema
    media_type: str = MEDIA_JSON
    description: str = ""
    alternatives: Mapping[str, Schema] = field(default_factory=dict)  # other media types of the same answer


@dataclass(frozen=True)
class Operation:
    """What a route declares: its input's shapes and its answers."""

    summary: str
    body: Schema | None = None
    body_required: bool = True
    form: Schema | None = None
    query: Mapping[str, Schema] = field(default_factory=dict)
    answers: Mapping[int, Answer] = field(default_factory=dict)
    refusals: tuple[int, ...] = COMMON_REFUSALS
    login: bool = True
    tags: tuple[str, ...] = ()


def file_answer(media_type: str, description: str = "", alternatives: Mapping[str, Schema] | None = None,
                schema: Schema | None = None) -> Answer:
    """An answer that is a file (CSV, MCAP, a JSON document to download); alternatives: other media types it may
    come as (?format=txt); schema: a JSON file's shape (its properties, as any JSON answer says them)."""
    textual = media_type in ("text/csv", "text/plain", "text/calendar", "application/x-ndjson")
    if schema is None:
        schema = OBJECT if media_type == MEDIA_JSON else (
            {"type": "string"} if textual else {"type": "string", "format": "binary"})
    return Answer(schema, media_type, description, dict(alternatives or {}))


def described(summary: str | None = None, *, body: Schema | None = None, body_required: bool = True,
              form: Schema | None = None,
              query: Mapping[str, Schema] | None = None,
              answers: Mapping[int, Schema | Answer] | None = None, refusals: tuple[int, ...] = (),
              login: bool = True, form_read_by_view: bool = False) -> Callable[[F], F]:
    """Declares a JSON route's contract (module docstring); answers default to {200: any JSON object}. refusals
    are the statuses beyond COMMON_REFUSALS this route answers with the error shape (409 busy, 503 robot_offline).
    body_required=False: a request with no body at all is let through (the view has defaults). form_read_by_view:
    the form is documented but not read here, because the view must read it itself (a large upload: the view raises
    the size limit for that request only after checking who sends it, then names a missing field itself)."""
    shaped = {status: answer if isinstance(answer, Answer) else Answer(answer)
              for status, answer in (answers or {200: OBJECT}).items()}
    validators = {"body": _validator(body), "form": None if form_read_by_view else _validator(form)}
    query = dict(query or {})

    def decorate(view: F) -> F:
        operation = Operation(
            summary=summary or " ".join((view.__doc__ or view.__name__).strip().split("\n\n")[0].split()),
            body=body, body_required=body_required, form=form, query=query, answers=shaped,
            refusals=tuple(sorted(set(COMMON_REFUSALS if login else (400, 404)) | set(refusals))), login=login)

        @functools.wraps(view)
        def checked(*args: Any, **kwargs: Any) -> Any:
            _check_query(query)
            if validators["body"] is not None and (body_required or request.get_data(cache=True)):
                _check(validators["body"], request.get_json(silent=True), "body")
            if validators["form"] is not None and request.mimetype == "multipart/form-data":
                files = {name: upload.filename or "" for name, upload in request.files.items()}  # a file is its bytes
                _check(validators["form"], {**request.form.to_dict(), **files}, "form")
            return view(*args, **kwargs)

        setattr(checked, ATTRIBUTE, operation)
        return checked  # type: ignore[return-value]

    return decorate


def operation_of(view: Callable[..., Any]) -> Operation | None:
    """The contract declared on a view (through any decorators wrapped around it), or None."""
    current: Any = view
    while current is not None:
        found = getattr(current, ATTRIBUTE, None)
        if isinstance(found, Operation):
            return found
        current = getattr(current, "__wrapped__", None)
    return None


# --- checking ----------------------------------------------------------------------------------------------------


def _validator(schema: Schema | None) -> Draft202012Validator | None:
    if schema is None:
        return None
    Draft202012Validator.check_schema(schema)
    return Draft202012Validator(schema)


def _field_name(path: Any, start: str) -> str:
    name = start
    for part in path:
        if isinstance(part, int):
            name += f"[{part}]"
        else:
            name = part if name in ("body", "form") else f"{name}.{part}"
    return name


def _check(validator: Draft202012Validator, value: Any, start: str) -> None:
    if start == "body" and not isinstance(value, dict):
        raise InvalidInput("body", gettext("Send a JSON object."))
    error = min(validator.iter_errors(value), key=lambda e: (len(e.path), list(map(str, e.path))), default=None)
    if error is not None:
        raise _refusal(error, start)


_KINDS = {"string": N_("text"), "integer": N_("a whole number"), "number": N_("a number"),
          "boolean": N_("true or false"), "object": N_("a JSON object"), "array": N_("a list"), "null": "null"}


def _refusal(error: ValidationError, start: str) -> InvalidInput:
    """The sentence for one schema error, naming the field."""
    name = _field_name(error.path, start)
    schema, kind = error.schema if isinstance(error.schema, dict) else {}, error.validator
    if kind == "required":
        missing = str(error.message).split("'")[1] if "'" in str(error.message) else "a field"
        name = missing if name in ("body", "form") else f"{name}.{missing}"
        return InvalidInput(name, gettext("%(name)s is required.", name=name))
    if kind == "type":
        kinds = schema.get("type")
        named = [str(k) for k in (kinds if isinstance(kinds, list) else [kinds])]
        wanted = str(gettext(" or ")).join(gettext(_KINDS[k]) if k in _KINDS else k for k in named)
        return InvalidInput(name, gettext("%(name)s must be %(wanted)s.", name=name, wanted=wanted))
    if kind in ("minimum", "maximum"):
        low, high = schema.get("minimum"), schema.get("maximum")
        return InvalidInput(name, _within(name, low, high))
    if kind in ("minLength", "maxLength"):
        low, high = schema.get("minLength", 0), schema.get("maxLength")
        if high is not None:
            return InvalidInput(name, gettext("%(name)s must be %(low)s to %(high)s characters long.", name=name,
                                              low=written_number(low), high=written_number(high)))
        return InvalidInput(name, gettext("%(name)s must be at least %(low)s characters long.", name=name,
                                          low=written_number(low)))
    if kind == "maxItems":
        return InvalidInput(name, gettext("%(name)s holds at most %(count)s items.", name=name,
                                          count=written_number(schema.get("maxItems"))))
    if kind in ("enum", "const"):
        allowed = ", ".join(map(str, schema.get("enum", [schema.get("const")])))
        return InvalidInput(name, gettext("%(name)s must be one of: %(allowed)s.", name=name, allowed=allowed))
    if kind == "pattern":
        # A schema's description is English (the API's document): said as it is.
        form = schema.get("description") or gettext("in the expected form")
        return InvalidInput(name, gettext("%(name)s must be %(form)s.", name=name, form=form))
    return InvalidInput(name, gettext("%(name)s is not allowed here: %(reason)s.", name=name,
                                      reason=schema.get("description", error.message)))


def _within(name: str, low: float | None, high: float | None) -> str:
    """The sentence for a number outside its schema's minimum and maximum."""
    if low is not None and high is not None:
        return str(gettext("%(name)s must be from %(low)s to %(high)s.", name=name, low=written_number(low),
                           high=written_number(high)))
    if low is not None:
        return str(gettext("%(name)s must be at least %(low)s.", name=name, low=written_number(low)))
    return str(gettext("%(name)s must be at most %(high)s.", name=name, high=written_number(high)))


def _check_query(query: Mapping[str, Schema]) -> None:
    """Each declared query parameter present: a whole number within its range, one of its values, or text of its
    length (the query string's own text rule ran before: validation._check_request_text)."""
    for name, schema in query.items():
        value = request.args.get(name)
        if value is None or value == "":
            continue
        if schema.get("type") == "integer":
            if decimal_int(value, schema.get("minimum", -(2**63)), schema.get("maximum", 2**63 - 1)) is None:
                low, high = schema.get("minimum"), schema.get("maximum")
                if low is not None and high is not None:
                    raise InvalidInput(name, gettext("%(name)s must be a whole number from %(low)s to %(high)s.",
                                                     name=name, low=written_number(low), high=written_number(high)))
                raise InvalidInput(name, gettext("%(name)s must be a whole number.", name=name))
        elif "enum" in schema and value not in schema["enum"]:
            raise InvalidInput(name, gettext("%(name)s must be one of: %(allowed)s.", name=name,
                                             allowed=", ".join(map(str, schema["enum"]))))
        elif len(value) > schema.get("maxLength", len(value)):
            raise InvalidInput(name, gettext("%(name)s must be at most %(high)s characters long.", name=name,
                                             high=written_number(schema["maxLength"])))
