"""The API described: the OpenAPI 3.1 document at /api/openapi.json and a page that reads it, /api/docs.

Both are public (they describe, they hold nothing of anyone's) and built from the routes' own contracts each time
they are asked for (a few milliseconds), so they cannot drift from the code.
"""

from __future__ import annotations

import json
from typing import Any

from flask import Blueprint, current_app, jsonify, render_template
from flask.typing import ResponseReturnValue

from middleware.api import document
from middleware.api.contract import OBJECT, STRING, Answer, described, obj, one_of

blueprint = Blueprint("api", __name__)


@blueprint.get("/api/openapi.json")
@described("The OpenAPI 3.1 document of every JSON route and WebSocket channel", answers={200: obj(
    ("openapi", "info", "paths", "components", "x-websocket"), description="OpenAPI 3.1 (its own schema says the rest)",
    openapi=one_of("3.1.0"), info=obj(("title", "version"), title=STRING, version=STRING), paths=OBJECT,
    components=OBJECT, **{"x-websocket": obj(("channels",), channels=OBJECT)})}, login=False)
def openapi() -> ResponseReturnValue:
    """The OpenAPI 3.1 document of every JSON route and WebSocket channel."""
    return jsonify(document.build(current_app))


def _operations(spec: dict[str, Any]) -> list[dict[str, Any]]:
    """The document's operations as the page lists them, grouped by tag in path order."""
    listed = []
    for path, item in spec["paths"].items():
        shared = item.get("parameters", [])
        for method, operation in item.items():
            if method == "parameters":
                continue
            body = operation.get("requestBody", {}).get("content", {})
            listed.append({
                "tag": operation["tags"][0], "method": method.upper(), "path": path,
                "id": operation["operationId"], "summary": operation["summary"],
                "login": operation.get("security") != [{}],
                "parameters": shared + operation.get("parameters", []),
                "body": {media: json.dumps(content["schema"], indent=1) for media, content in body.items()},
                "responses": [(status, json.dumps(response["content"][next(iter(response["content"]))]["schema"],
                                                  indent=1) if "content" in response else None,
                               response.get("description", ""))
                              for status, response in operation["responses"].items()],
            })
    return listed


@blueprint.get("/api/docs")
@described(answers={200: Answer({"type": "string"}, "text/html", "the page")}, login=False)
def docs_page() -> ResponseReturnValue:
    """A readable page of the document: every operation, its input and answers, and the channels."""
    spec = document.build(current_app)
    operations = _operations(spec)
    tags = sorted({operation["tag"] for operation in operations})
    channels = {rule: {**described_channel,
                       "receives": [json.dumps(m, indent=1) for m in described_channel["receives"]],
                       "sends": [json.dumps(m, indent=1) for m in described_channel["sends"]]}
                for rule, described_channel in spec["x-websocket"]["channels"].items()}
    return render_template("api/docs.html", spec=spec, operations=operations, tags=tags, channels=channels,
                           close_codes=spec["x-websocket"]["closeCodes"],
                           error_shape=json.dumps(spec["components"]["schemas"]["Error"], indent=1))
