"""A test LMS (what pylti1p3's own tests build): its own RSA keys and key set, signed id tokens, an OIDC
authorization endpoint that posts the launch back, a token endpoint that checks the tool's signed assertion
against the tool's JWKS, a recording AGS score endpoint that can be told to fail, an NRPS roster, a deep-linking
return that checks the tool's signature, and a course page that frames the tool. Served on a free loopback port."""

from __future__ import annotations

import html
import json
import threading
from typing import Any

from werkzeug.serving import make_server
from werkzeug.wrappers import Request, Response

from middleware.lti.demo_platform import (
    CLAIM,
    INSTRUCTOR,
    LEARNER,
    LINEITEM_SCOPE,
    LMS_ADMIN,
    SCORE_SCOPE,
    LmsCourse,
    PlatformSide,
    new_key,
)

__all__ = ["CLAIM", "INSTRUCTOR", "LEARNER", "LINEITEM_SCOPE", "LMS_ADMIN", "SCORE_SCOPE", "LmsPlatform", "new_key"]


class LmsPlatform(PlatformSide):
    """The LMS (its LTI side shared with the demo LMS: middleware/lti/demo_platform.py), served on a free port."""

    def __init__(self, tool_url: str = "", client_id: str = "telelab-client", deployment_id: str = "dep-1") -> None:
        self.scores: list[dict[str, Any]] = []
        self.fail_scores = 0  # answer the next N score posts with 503
        self.members: list[dict[str, Any]] = []
        self.deep_link_returns: list[dict[str, Any]] = []
        self.pending: dict[str, dict[str, Any]] = {}  # login_hint -> claims for /auth
        self._server = make_server("127.0.0.1", 0, self._wsgi, threaded=True)
        super().__init__(f"http://127.0.0.1:{self._server.server_port}", tool_url, client_id, deployment_id)
        self._thread = threading.Thread(target=self._server.serve_forever, kwargs={"poll_interval": 0.05},
                                        daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stops serving."""
        self._server.shutdown()
        self._server.server_close()

    def registration(self, name: str = "Test LMS") -> dict[str, str]:
        """What the tool's admin enters."""
        return super().registration(name)

    def claims(self, nonce: str, sub: str, roles: list[str], *, context: str | None = "course-1",  # type: ignore[override]
               **kwargs: Any) -> dict[str, Any]:
        """A launch's claims for the tool, from the LMS course "ROB101" (context) unless None."""
        course = LmsCourse(context, "ROB101", "Mobile robotics") if context else None
        return super().claims(nonce, sub, roles, course=course, **kwargs)

    # The LMS's endpoints.
    def _wsgi(self, environ: dict[str, Any], start_response: Any) -> Any:
        request = Request(environ)
        handler = {"/jwks": self._jwks, "/auth": self._auth, "/token": self._token, "/memberships": self._members,
                   "/deep-link-return": self._deep_link_return, "/course": self._course}.get(request.path)
        if handler is None and request.path.startswith("/lineitems/") and request.path.endswith("/scores"):
            handler = self._score
        response = handler(request) if handler else Response("not found", 404)
        return response(environ, start_response)

    def _jwks(self, _request: Request) -> Response:
        return Response(json.dumps(self.key_set()), content_type="application/json")

    def _auth(self, request: Request) -> Response:
        """The OIDC authorization endpoint: posts the launch prepared for login_hint back to redirect_uri."""
        prepared = self.pending[request.args["login_hint"]]
        claims = self.claims(request.args["nonce"], **prepared)
        return Response(self.launch_page(request.args["redirect_uri"], request.args["state"], claims),
                        content_type="text/html")

    def _token(self, request: Request) -> Response:
        return Response(json.dumps(self.access_token(request.form["client_assertion"])),
                        content_type="application/json")

    def _score(self, request: Request) -> Response:
        if not request.headers.get("Authorization", "").startswith("Bearer token-"):
            return Response("no token", 401)
        if self.fail_scores > 0:
            self.fail_scores -= 1
            return Response("gradebook is down for maintenance", 503)
        self.scores.append({"lineitem": request.path.removesuffix("/scores"), **json.loads(request.data)})
        return Response("", 204)

    def _members(self, _request: Request) -> Response:
        body = {"id": self.url + "/memberships", "context": {"id": "course-1"}, "members": self.members}
        return Response(json.dumps(body), content_type="application/vnd.ims.lti-nrps.v2.membershipcontainer+json")

    def _deep_link_return(self, request: Request) -> Response:
        self.deep_link_returns.append(self.deep_link_answer(request.form["JWT"]))
        return Response("<p id='placed'>Placed in the course.</p>", content_type="text/html")

    def _course(self, request: Request) -> Response:
        """An LMS course page framing the tool's launch for login_hint."""
        tool = html.escape(self.login_url(request.args["login_hint"]))
        page = ('<!doctype html><meta name="viewport" content="width=device-width, initial-scale=1">'
                '<title>LMS course</title><h1>LMS course</h1>'
                f'<iframe id="tool" src="{tool}" style="width:100%;height:900px;border:1px solid #888" '
                'allow="fullscreen"></iframe>')
        return Response(page, content_type="text/html")
