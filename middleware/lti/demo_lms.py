"""The demo LMS of `make run`: a small stand-in for a university's LMS (Moodle, Canvas), served on 127.0.0.1 on a
port of its own, so a person can walk Telelab's LTI journey with no real LMS. It is not Telelab: its pages are the
LMS's (English, its own look), labelled as a stand-in on every page.

One LMS course with two people, a learner and an instructor. Its course page launches either of them into
Telelab inside a frame, lets the instructor add Telelab content (deep linking), lists what was placed, and its
gradebook shows the grades Telelab passed back (AGS). Its LTI side (keys, claims, signatures) is
`demo_platform.PlatformSide`, which the test LMS shares. Its key and what was placed and graded are kept in a
JSON file beside the lab's instance data, so a restart keeps them.

Run as `python -m middleware.lti.demo_lms --port P --tool http://127.0.0.1:5000 --state FILE` (`demo_setup.py`
starts it for `telelab up`).
"""

from __future__ import annotations

import argparse
import html
import json
import os
import threading
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from jwcrypto.jwk import JWK  # type: ignore[import-untyped]
from werkzeug.serving import make_server
from werkzeug.wrappers import Request, Response

from middleware.lti.demo_platform import INSTRUCTOR, LEARNER, LmsCourse, PlatformSide

CLIENT_ID = "telelab-demo-lms"
DEPLOYMENT_ID = "demo-deployment"
COURSE = LmsCourse("demo-lms-course", "ROBOTICS", "Mobile robotics (demo LMS course)")
# The LMS's two people: (subject, given name, full name, LTI role).
PEOPLE = {"learner": ("demo-lms-learner", "Lea", "Lea Learner", LEARNER),
          "instructor": ("demo-lms-instructor", "Ian", "Ian Instructor", INSTRUCTOR)}
HOME_HINT, DEEP_LINK_HINT = "home", "deep-link"
MAX_ITEMS = 200
LANGUAGES = {"en": "English", "es": "Español"}  # the launches' locale, as an LMS sends its user's language
READY_LINE = "demo LMS at "
_STYLE = """
body{font-family:system-ui,sans-serif;margin:0;background:#f4f1ea;color:#222}
header{background:#6b3e26;color:#fff;padding:.6rem 1rem;display:flex;gap:1rem;align-items:baseline;flex-wrap:wrap}
header a{color:#fff}header strong{font-size:1.2rem}.standin{background:#ffd54f;color:#222;padding:.1rem .5rem;
border-radius:4px;font-size:.9rem}main{padding:1rem;max-width:70rem;margin:auto}section{background:#fff;
border:1px solid #d8cfc0;border-radius:6px;padding:.8rem 1rem;margin:0 0 1rem}a.button{display:inline-block;
background:#6b3e26;color:#fff;padding:.45rem .8rem;border-radius:4px;text-decoration:none;margin:.2rem .3rem .2rem 0}
.scroll{overflow-x:auto}table{border-collapse:collapse;width:100%}
th,td{border-bottom:1px solid #e5ddd0;padding:.4rem;text-align:left}
iframe{width:100%;height:80vh;border:1px solid #999;background:#fff}
"""


def _language(request: Request) -> str:
    lang = request.args.get("lang", "en")
    return lang if lang in LANGUAGES else "en"


def _page(title: str, body: str) -> Response:
    text = (f'<!doctype html><html lang="en"><meta charset="utf-8"><meta name="viewport" '
            f'content="width=device-width, initial-scale=1"><title>{html.escape(title)} · Demo LMS</title>'
            f'<style>{_STYLE}</style><header><strong>Demo LMS</strong><span class="standin" id="stand-in">A stand-in '
            'for your LMS (Moodle, Canvas…), to try Telelab\'s LTI: not a real LMS</span>'
            '<a href="/">Course</a><a href="/gradebook">Gradebook</a></header>'
            f'<main>{body}</main></html>')
    return Response(text, content_type="text/html; charset=utf-8")


class DemoLms:
    """The stand-in LMS: its LTI side, what was placed in its course, the grades it received."""

    def __init__(self, url: str, tool_url: str, state_path: Path) -> None:
        self.state_path = state_path
        self._lock = threading.Lock()
        state = json.loads(state_path.read_text()) if state_path.exists() else {}
        self.items: list[dict[str, Any]] = state.get("items", [])
        self.scores: list[dict[str, Any]] = state.get("scores", [])
        pem = state.get("private_pem", "")
        public = {}
        if pem:
            public = json.loads(JWK.from_pem(pem.encode()).export_public())
            public.update({"kid": JWK.from_pem(pem.encode()).thumbprint(), "alg": "RS256", "use": "sig"})
        self.side = PlatformSide(url, tool_url, CLIENT_ID, DEPLOYMENT_ID, pem, public)
        self._save()

    def _save(self) -> None:
        self.state_path.parent.mkdir(parents=True, exist_ok=True)
        state = {"private_pem": self.side.private_pem, "items": self.items, "scores": self.scores}
        self.state_path.write_text(json.dumps(state, indent=1))

    def __call__(self, environ: dict[str, Any], start_response: Any) -> Any:
        request = Request(environ)
        handler = {"/": self.course_page, "/launch": self.launch_page, "/gradebook": self.gradebook,
                   "/auth": self.authorize, "/token": self.token, "/jwks": self.jwks, "/memberships": self.members,
                   "/deep-link-return": self.deep_link_return}.get(request.path)
        if handler is None and request.path.startswith("/lineitems/") and request.path.endswith("/scores"):
            handler = self.score
        try:
            response = handler(request) if handler else _page("Not found", "<p>There is no such page.</p>")
        except (KeyError, ValueError) as error:  # a hand-typed address: the LMS says so, never a trace
            kind = html.escape(type(error).__name__)
            response = _page("Not understood", f"<p>This request is not one the demo LMS makes ({kind}).</p>")
            response.status_code = 400
        return response(environ, start_response)

    # Pages a person reads.
    def course_page(self, request: Request) -> Response:
        """The LMS course: Telelab's home for either person, the placed activities, deep linking; the launches'
        language (their launch_presentation locale) chosen here."""
        lang = _language(request)
        q = f"&lang={lang}"
        rows = "".join(
            f'<tr data-item="{item["id"]}"><td>{html.escape(item["title"])}</td>'
            f'<td>{"a gradebook column" if item.get("lineitem") else ""}</td><td>'
            f'<a class="button" href="/launch?person=learner&item={item["id"]}{q}">Open as Lea (learner)</a>'
            f'<a class="button" href="/launch?person=instructor&item={item["id"]}{q}">Open as Ian (instructor)</a>'
            '</td></tr>' for item in self.items)
        placed = (f'<div class="scroll"><table id="activities"><thead><tr><th>Activity</th><th>Grades</th><th></th>'
                  f'</tr></thead><tbody>{rows}</tbody></table></div>' if self.items else
                  '<p id="no-activities">Nothing placed yet: open "Add Telelab content" as the instructor.</p>')
        languages = " · ".join(f"<strong>{name}</strong>" if code == lang else f'<a href="/?lang={code}">{name}</a>'
                               for code, name in LANGUAGES.items())
        body = (f'<h1>{html.escape(COURSE.title)}</h1>'
                f'<p id="launch-language">The LMS launches Telelab in: {languages}</p>'
                '<section><h2>Telelab, the remote robotics lab</h2><p>Opens Telelab inside this page, signed in '
                'as the person you choose (by the LMS, with LTI 1.3).</p>'
                f'<a class="button" id="launch-learner" href="/launch?person=learner{q}">Open Telelab as Lea '
                f'(learner)</a><a class="button" id="launch-instructor" href="/launch?person=instructor{q}">Open '
                'Telelab as Ian (instructor)</a></section>'
                '<section><h2>Course activities from Telelab</h2>' + placed +
                f'<p><a class="button" id="add-content" href="/launch?person=instructor&deep_link=1{q}">Add Telelab '
                'content (as Ian, the instructor)</a></p></section>')
        return _page(COURSE.title, body)

    def launch_page(self, request: Request) -> Response:
        """A launch inside a frame of the LMS's page, as the chosen person."""
        person = request.args["person"]
        if person not in PEOPLE:
            raise KeyError(person)
        hint = DEEP_LINK_HINT if request.args.get("deep_link") else request.args.get("item", HOME_HINT)
        name = PEOPLE[person][2]
        what = ("Adding Telelab content" if hint == DEEP_LINK_HINT else
                "Telelab" if hint == HOME_HINT else self._item(hint)["title"])
        lang = _language(request)
        body = (f'<p><a href="/?lang={lang}">← Back to the course</a> · <span id="who">{html.escape(name)}</span>: '
                f'{html.escape(what)}</p><iframe id="tool" title="Telelab" allow="fullscreen" '
                f'src="{html.escape(self.side.login_url(person, f"{hint}@{lang}"))}"></iframe>')
        return _page(what, body)

    def gradebook(self, _request: Request) -> Response:
        """The grades Telelab passed back, one column per graded activity."""
        columns = [item for item in self.items if item.get("lineitem")]
        latest: dict[tuple[str, str], dict[str, Any]] = {}
        for score in self.scores:
            latest[(score["userId"], score["lineitem"])] = score
        head = "".join(f"<th>{html.escape(item['title'])}</th>" for item in columns)
        rows = ""
        for _key, (subject, _given, name, _role) in PEOPLE.items():
            cells = ""
            for item in columns:
                got = latest.get((subject, item["lineitem"]))
                cells += (f'<td data-grade="{html.escape(item["title"])}">{got["scoreGiven"]:g} / '
                          f'{got["scoreMaximum"]:g}<br><small>{html.escape(got.get("timestamp", "")[:19])}</small>'
                          '</td>' if got else "<td>—</td>")
            rows += f"<tr><th scope='row'>{html.escape(name)}</th>{cells}</tr>"
        table = (f'<div class="scroll"><table id="gradebook"><thead><tr><th>Person</th>{head}</tr></thead>'
                 f'<tbody>{rows}</tbody></table></div>'
                 if columns else '<p id="no-columns">No graded activity yet: place a Telelab test in the course.</p>')
        return _page("Gradebook", f"<h1>Gradebook</h1><section>{table}</section>")

    # The LMS's LTI endpoints.
    def _item(self, key: str) -> dict[str, Any]:
        return next(item for item in self.items if str(item["id"]) == key)

    def authorize(self, request: Request) -> Response:
        """The OIDC authorization endpoint: the launch of login_hint's person for lti_message_hint."""
        subject, given, name, role = PEOPLE[request.args["login_hint"]]
        redirect_uri = request.args["redirect_uri"]
        if redirect_uri != self.side.tool_url + "/lti/launch" or request.args.get("client_id") != CLIENT_ID:
            raise ValueError("redirect_uri")  # only the registered tool's launch address
        hint, _, lang = request.args.get("lti_message_hint", HOME_HINT).partition("@")
        extra: dict[str, Any] = {"given_name": given, "name": name, "course": COURSE,
                                 "locale": lang if lang in LANGUAGES else "en"}
        if hint == DEEP_LINK_HINT:
            extra["deep_link"] = True
        elif hint != HOME_HINT:
            item = self._item(hint)
            extra.update(custom=item["custom"], lineitem=item.get("lineitem"), resource_link=f"item-{item['id']}")
        claims = self.side.claims(request.args["nonce"], subject, [role], **extra)
        return Response(self.side.launch_page(redirect_uri, request.args["state"], claims),
                        content_type="text/html; charset=utf-8")

    def token(self, request: Request) -> Response:
        """A service token for the tool, once its signed request checks against the tool's key set."""
        try:
            answer = self.side.access_token(request.form["client_assertion"])
        except Exception:  # noqa: BLE001 - any failed check is the same refusal to the tool
            return Response(json.dumps({"error": "invalid_client"}), 401, content_type="application/json")
        return Response(json.dumps(answer), content_type="application/json")

    def jwks(self, _request: Request) -> Response:
        """The LMS's public key set."""
        return Response(json.dumps(self.side.key_set()), content_type="application/json")

    def members(self, _request: Request) -> Response:
        """The course roster (Names and Role Provisioning)."""
        members = [{"user_id": subject, "name": name, "given_name": given, "status": "Active", "roles": [role]}
                   for subject, given, name, role in PEOPLE.values()]
        body = {"id": self.side.url + "/memberships", "context": {"id": COURSE.id}, "members": members}
        return Response(json.dumps(body), content_type="application/vnd.ims.lti-nrps.v2.membershipcontainer+json")

    def score(self, request: Request) -> Response:
        """A grade from the tool for a line item (AGS), given a service token."""
        lineitem = self.side.url + request.path.removesuffix("/scores")
        if not request.headers.get("Authorization", "").startswith("Bearer token-"):
            return Response("no token", 401)
        if not any(item.get("lineitem") == lineitem for item in self.items):
            return Response("no such line item", 404)
        body = json.loads(request.get_data(as_text=True))
        with self._lock:
            self.scores.append({"lineitem": lineitem, "userId": str(body["userId"]),
                                "scoreGiven": float(body["scoreGiven"]), "scoreMaximum": float(body["scoreMaximum"]),
                                "timestamp": str(body.get("timestamp") or datetime.now(UTC).isoformat())})
            self._save()
        return Response("", 204)

    def deep_link_return(self, request: Request) -> Response:
        """The tool's deep-linking answer: its items become course activities (a test gets a gradebook column)."""
        try:
            answer = self.side.deep_link_answer(request.form["JWT"])
        except Exception:  # noqa: BLE001 - an answer that does not check is refused, whatever failed
            return _page("Refused", "<p>The answer was not signed by the registered tool.</p>")
        placed = []
        with self._lock:
            for content in answer.get("https://purl.imsglobal.org/spec/lti-dl/claim/content_items", [])[:50]:
                if len(self.items) >= MAX_ITEMS:
                    break
                item_id = max((item["id"] for item in self.items), default=0) + 1
                title = str(content.get("title", "Telelab"))[:200]
                item: dict[str, Any] = {"id": item_id, "title": title, "custom": {
                    str(k): str(v) for k, v in (content.get("custom") or {}).items()}}
                if isinstance(content.get("lineItem"), dict):
                    item["lineitem"] = f"{self.side.url}/lineitems/{item_id}"
                self.items.append(item)
                placed.append(title)
            self._save()
        names = "".join(f"<li>{html.escape(title)}</li>" for title in placed)
        return _page("Placed", f'<h1 id="placed">Placed in the course</h1><ul>{names}</ul>'
                               '<p><a class="button" href="/" target="_top" id="back-to-course">Back to the '
                               'course</a></p>')


def _exit_with(parent_pid: int) -> None:
    """Ends this process when the launcher that started it is gone (even killed: it cannot stop us then)."""
    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(0)

    threading.Thread(target=watch, name="demo-lms-parent-watch", daemon=True).start()


def serve(port: int, tool_url: str, state_path: Path, parent_pid: int | None = None) -> None:
    """Serves the demo LMS on 127.0.0.1:port (0: a free one) until interrupted; its first line says its address."""
    server = make_server("127.0.0.1", port, lambda environ, start: [], threaded=True)
    url = f"http://127.0.0.1:{server.server_port}"
    server.app = DemoLms(url, tool_url.rstrip("/"), state_path)  # its issuer is the address it got
    if parent_pid:
        _exit_with(parent_pid)
    print(f"{READY_LINE}{url}", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Telelab's demo LMS (a stand-in, for trying LTI)")
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--tool", required=True, help="Telelab's address, e.g. http://127.0.0.1:5000")
    parser.add_argument("--state", type=Path, required=True, help="the JSON file keeping its key, items and grades")
    parser.add_argument("--parent-pid", type=int, default=0, help="exit when this process is gone")
    args = parser.parse_args(argv)
    serve(args.port, args.tool, args.state, args.parent_pid)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
