"""The OpenAPI 3.1 document of the JSON API, generated with apispec from the routes' own contracts.

Each `/api/` rule of the app's URL map is one path; each of its methods an operation, made from the
`@described(...)` contract on its view (`contract.py`): path parameters from the rule's converters, the query,
the JSON body or multipart form, the answers and the refusals in the one error shape. A rule whose view
declares nothing is listed by `undescribed()` (a test fails on it) and left out of the document, never guessed.
The `/ws/link` channels are described in the same document under `x-websocket` (`channels.py`).
"""

from __future__ import annotations

import re
from typing import Any

from apispec import APISpec
from flask import Flask
from werkzeug.routing import Rule

from middleware.api import channels
from middleware.api.contract import ERROR, MEDIA_JSON, Operation, Schema, operation_of

API_PREFIX = "/api/"
VERSION = "1"
_CONVERTED = re.compile(r"<(?:(?P<converter>[a-zA-Z_][a-zA-Z0-9_]*)(?:\([^>]*\))?:)?(?P<name>[a-zA-Z_][a-zA-Z0-9_]*)>")
_INT_PARAMETER: Schema = {"type": "integer", "minimum": 0, "maximum": 2**31 - 1}
_TEXT_PARAMETER: Schema = {"type": "string", "minLength": 1, "maxLength": 200}
_STATUS_WORDS = {400: "Bad input: the field is named", 401: "Not logged in (or the login ended)",
                 403: "Not allowed for this user", 404: "Nothing there (or not visible to this user)",
                 409: "In conflict with the lab's state (busy, taken, already done)", 413: "Too large",
                 422: "Understood but refused", 429: "Too many at once; try again later",
                 503: "A robot or the farm does not answer"}


def api_rules(app: Flask) -> list[Rule]:
    """The JSON API's rules (WebSocket channels are not HTTP operations)."""
    return sorted((rule for rule in app.url_map.iter_rules()
                   if rule.rule.startswith(API_PREFIX) and not rule.websocket),
                  key=lambda rule: rule.rule)


def methods_of(rule: Rule) -> list[str]:
    """The rule's methods that are operations (HEAD and OPTIONS are Flask's own)."""
    return sorted((rule.methods or set()) - {"HEAD", "OPTIONS"})


def undescribed(app: Flask) -> list[str]:
    """"METHOD /rule" of every JSON route whose view declares no contract."""
    return [f"{method} {rule.rule}" for rule in api_rules(app) for method in methods_of(rule)
            if operation_of(app.view_functions[rule.endpoint]) is None]


def openapi_path(rule: str) -> str:
    """/api/plans/<int:plan_id> -> /api/plans/{plan_id}"""
    return _CONVERTED.sub(lambda found: "{" + found.group("name") + "}", rule)


def _path_parameters(rule: Rule) -> list[dict[str, Any]]:
    parameters = []
    for found in _CONVERTED.finditer(rule.rule):
        integer = found.group("converter") == "int"
        parameters.append({"name": found.group("name"), "in": "path", "required": True,
                           "schema": dict(_INT_PARAMETER if integer else _TEXT_PARAMETER)})
    return parameters


def _operation(rule: Rule, method: str, declared: Operation) -> dict[str, Any]:
    operation: dict[str, Any] = {
        "operationId": f"{rule.endpoint}.{method.lower()}", "summary": declared.summary,
        "tags": [rule.endpoint.split(".")[0]],
        "parameters": [{"name": name, "in": "query", "required": False, "schema": schema}
                       for name, schema in declared.query.items()],
        "responses": {},
    }
    if declared.body is not None:
        operation["requestBody"] = {"required": declared.body_required,
                                    "content": {MEDIA_JSON: {"schema": declared.body}}}
    elif declared.form is not None:
        operation["requestBody"] = {"required": True, "content": {"multipart/form-data": {"schema": declared.form}}}
    for status, answer in declared.answers.items():
        content = {answer.media_type: {"schema": answer.schema}}
        content.update({media: {"schema": schema} for media, schema in answer.alternatives.items()})
        operation["responses"][str(status)] = {"description": answer.description or "Done", "content": content}
    for status in declared.refusals:
        operation["responses"].setdefault(str(status), "Refused")
    if declared.login:
        operation["security"] = [{"session": []}]
    else:
        operation["security"] = [{}]
    return operation


def build(app: Flask) -> dict[str, Any]:
    """The OpenAPI 3.1 document of app's JSON routes and WebSocket channels."""
    spec = APISpec(
        title="Telelab API", version=VERSION, openapi_version="3.1.0",
        info={"description": (
            "Every JSON route of the lab. Log in with the login form (POST /login); the session cookie then "
            "authenticates each call, and a call that changes something carries the page's CSRF token in the "
            "X-CSRFToken header. A refusal is JSON {\"error\": {\"code\", \"message\", \"field\"}} with its status.")},
    )
    spec.components.schema("Error", ERROR)
    spec.components.security_scheme(
        "session", {"type": "apiKey", "in": "cookie", "name": app.config.get("SESSION_COOKIE_NAME", "session")})
    spec.components.security_scheme("csrf", {"type": "apiKey", "in": "header", "name": "X-CSRFToken"})
    spec.components.response("Refused", {
        "description": "Refused: a stable code, a sentence and the field at fault",
        "content": {MEDIA_JSON: {"schema": {"$ref": "#/components/schemas/Error"}}}})
    for rule in api_rules(app):
        view = app.view_functions[rule.endpoint]
        declared = operation_of(view)
        if declared is None:
            continue
        operations = {}
        for method in methods_of(rule):
            operation = _operation(rule, method, declared)
            for status in list(operation["responses"]):
                if operation["responses"][status] == "Refused":
                    operation["responses"][status] = {"$ref": "#/components/responses/Refused"}
            operations[method.lower()] = operation
        spec.path(path=openapi_path(rule.rule), operations=operations, parameters=_path_parameters(rule))
    document = spec.to_dict()
    document["x-websocket"] = channels.describe(app)
    for operation in (op for item in document["paths"].values() for op in item.values() if isinstance(op, dict)):
        for status, response in operation.get("responses", {}).items():
            if isinstance(response, dict) and "$ref" in response:
                response.setdefault("description", _STATUS_WORDS.get(int(status), "Refused"))
    return document
