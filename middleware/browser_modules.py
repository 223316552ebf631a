"""The import map naming the browser libraries that `make run` / `make test` install under
client_ui/static/vendor (three.js, from the npm registry at the version its package-lock.json pins), and the CSP
source that lets exactly this inline map run: pages `import * as THREE from "three"`, with no bundler and no build
step."""

from __future__ import annotations

import base64
import hashlib
import json

from flask import Flask
from markupsafe import Markup

VENDOR_MODULES = {
    "three": "vendor/node_modules/three/build/three.module.js",
    "three/addons/": "vendor/node_modules/three/examples/jsm/",
    # CodeMirror 6 for the exercises' editor (every bare specifier its ES modules import has an entry).
    "codemirror": "vendor/node_modules/codemirror/dist/index.js",
    "@codemirror/autocomplete": "vendor/node_modules/@codemirror/autocomplete/dist/index.js",
    "@codemirror/commands": "vendor/node_modules/@codemirror/commands/dist/index.js",
    "@codemirror/lang-python": "vendor/node_modules/@codemirror/lang-python/dist/index.js",
    "@codemirror/language": "vendor/node_modules/@codemirror/language/dist/index.js",
    "@codemirror/lint": "vendor/node_modules/@codemirror/lint/dist/index.js",
    "@codemirror/search": "vendor/node_modules/@codemirror/search/dist/index.js",
    "@codemirror/state": "vendor/node_modules/@codemirror/state/dist/index.js",
    "@codemirror/streamparser": "vendor/node_modules/@codemirror/streamparser/dist/index.js",
    "@codemirror/view": "vendor/node_modules/@codemirror/view/dist/index.js",
    "@lezer/common": "vendor/node_modules/@lezer/common/dist/index.js",
    "@lezer/highlight": "vendor/node_modules/@lezer/highlight/dist/index.js",
    "@lezer/lr": "vendor/node_modules/@lezer/lr/dist/index.js",
    "@lezer/python": "vendor/node_modules/@lezer/python/dist/index.js",
    "@marijn/find-cluster-break": "vendor/node_modules/@marijn/find-cluster-break/src/index.js",
    "crelt": "vendor/node_modules/crelt/index.js",
    "style-mod": "vendor/node_modules/style-mod/src/style-mod.js",
    "w3c-keyname": "vendor/node_modules/w3c-keyname/index.js",
}


def import_map_text(static_url_path: str) -> str:
    """The JSON of the import map, with the static files' URL prefix."""
    prefix = static_url_path.rstrip("/") + "/"
    return json.dumps({"imports": {name: prefix + path for name, path in VENDOR_MODULES.items()}},
                      separators=(",", ":"), sort_keys=True)


def csp_hash_source(text: str) -> str:
    """The script-src source that allows one inline script whose text is exactly text."""
    return "'sha256-" + base64.b64encode(hashlib.sha256(text.encode()).digest()).decode() + "'"


def init_app(app: Flask) -> str:
    """Gives templates `import_map` (the whole <script type="importmap"> element); returns its CSP source."""
    text = import_map_text(app.static_url_path or "/static")
    # The text is JSON of fixed paths (no "<"), so it goes into the page as it is and its hash holds.
    element = Markup(f'<script type="importmap">{text}</script>')
    app.jinja_env.globals["import_map"] = element
    return csp_hash_source(text)
