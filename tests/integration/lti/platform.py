"""A test LMS (what pylti1p3's own tests build): its own RSA keys and key set, signed id tokens, an OIDC
authorization endpoint that posts the launch back, a token endpoint that checks the tool's signed assertion
against the tool's JWKS, a recording AGS score endpoint that can be told to fail, an NRPS roster, a deep-linking
return that checks the tool's signature, and a course page that frames the tool. Served on a free loopback port."""

from __future__ import annotations

import html
import json
import threading
import time
import uuid
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import urlencode

import jwt
import requests
from jwcrypto.jwk import JWK
from werkzeug.serving import make_server
from werkzeug.wrappers import Request, Response

CLAIM = "https://purl.imsglobal.org/spec/lti/claim/"
LEARNER = "http://purl.imsglobal.org/vocab/lis/v2/membership#Learner"
INSTRUCTOR = "http://purl.imsglobal.org/vocab/lis/v2/membership#Instructor"
LMS_ADMIN = "http://purl.imsglobal.org/vocab/lis/v2/institution/person#Administrator"
SCORE_SCOPE = "https://purl.imsglobal.org/spec/lti-ags/scope/score"
LINEITEM_SCOPE = "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem"


def new_key() -> tuple[str, dict[str, Any]]:
    """(private PEM, public JWK with kid) of a fresh RSA key."""
    key = JWK.generate(kty="RSA", size=2048)
    public = json.loads(key.export_public())
    public.update({"kid": key.thumbprint(), "alg": "RS256", "use": "sig"})
    return key.export_to_pem(private_key=True, password=None).decode(), public


@dataclass
class LmsPlatform:
    """The LMS: issuer = its own URL; client_id and deployment given to the tool."""

    client_id: str = "telelab-client"
    deployment_id: str = "dep-1"
    tool_url: str = ""
    scores: list[dict[str, Any]] = field(default_factory=list)
    fail_scores: int = 0  # answer the next N score posts with 503
    members: list[dict[str, Any]] = field(default_factory=list)
    deep_link_returns: list[dict[str, Any]] = field(default_factory=list)
    pending: dict[str, dict[str, Any]] = field(default_factory=dict)  # login_hint -> claims for /auth

    def __post_init__(self) -> None:
        self.private_pem, self.public_jwk = new_key()
        self._server = make_server("127.0.0.1", 0, self._wsgi, threaded=True)
        self.url = f"http://127.0.0.1:{self._server.server_port}"
        self._thread = threading.Thread(target=self._server.serve_forever, kwargs={"poll_interval": 0.05},
                                        daemon=True)
        self._thread.start()

    @property
    def issuer(self) -> str:
        """The issuer (its own origin)."""
        return self.url

    def stop(self) -> None:
        """Stops serving."""
        self._server.shutdown()
        self._server.server_close()

    def registration(self) -> dict[str, str]:
        """What the tool's admin enters."""
        return {"name": "Test LMS", "issuer": self.issuer, "client_id": self.client_id,
                "deployment_ids": self.deployment_id, "auth_login_url": self.url + "/auth",
                "auth_token_url": self.url + "/token", "key_set_url": self.url + "/jwks"}

    def claims(self, nonce: str, sub: str, roles: list[str], *, context: str | None = "course-1",
               custom: dict[str, str] | None = None, lineitem: str | None = None, deep_link: bool = False,
               locale: str | None = None, **extra: Any) -> dict[str, Any]:
        """A launch's claims for the tool."""
        now = int(time.time())
        body: dict[str, Any] = {
            "iss": self.issuer, "aud": self.client_id, "sub": sub, "nonce": nonce, "iat": now, "exp": now + 300,
            "given_name": sub.split("-")[0], "name": sub,
            CLAIM + "deployment_id": self.deployment_id, CLAIM + "version": "1.3.0", CLAIM + "roles": roles,
            CLAIM + "message_type": "LtiDeepLinkingRequest" if deep_link else "LtiResourceLinkRequest",
            CLAIM + "target_link_uri": self.tool_url + "/lti/launch",
            "https://purl.imsglobal.org/spec/lti-nrps/claim/namesroleservice": {
                "context_memberships_url": self.url + "/memberships", "service_versions": ["2.0"]},
            "https://purl.imsglobal.org/spec/lti-ags/claim/endpoint": {
                "scope": [SCORE_SCOPE, LINEITEM_SCOPE], "lineitems": self.url + "/lineitems",
                **({"lineitem": lineitem} if lineitem else {})},
        }
        if locale:
            body[CLAIM + "launch_presentation"] = {"locale": locale}
        if context:
            body[CLAIM + "context"] = {"id": context, "label": "ROB101", "title": "Mobile robotics"}
        if deep_link:
            body["https://purl.imsglobal.org/spec/lti-dl/claim/deep_linking_settings"] = {
                "deep_link_return_url": self.url + "/deep-link-return", "accept_types": ["ltiResourceLink"],
                "accept_presentation_document_targets": ["iframe", "window"], "accept_multiple": True}
        else:
            body[CLAIM + "resource_link"] = {"id": "link-" + (custom or {}).get("telelab_target", "home")}
        if custom:
            body[CLAIM + "custom"] = custom
        body.update(extra)
        return body

    def sign(self, claims: dict[str, Any], key: str | None = None, kid: str | None = None) -> str:
        """claims signed with the platform's key (or another)."""
        return jwt.encode(claims, key or self.private_pem, algorithm="RS256",
                          headers={"kid": kid or self.public_jwk["kid"]})

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
        return Response(json.dumps({"keys": [self.public_jwk]}), content_type="application/json")

    def _auth(self, request: Request) -> Response:
        """The OIDC authorization endpoint: posts the launch prepared for login_hint back to redirect_uri."""
        prepared = self.pending[request.args["login_hint"]]
        claims = self.claims(request.args["nonce"], **prepared)
        fields = {"id_token": self.sign(claims), "state": request.args["state"]}
        inputs = "".join(f'<input type="hidden" name="{k}" value="{html.escape(v)}">' for k, v in fields.items())
        page = (f'<form id="f" method="post" action="{html.escape(request.args["redirect_uri"])}">{inputs}'
                '<button>Go</button></form><script>document.getElementById("f").submit()</script>')
        return Response(page, content_type="text/html")

    def _tool_keys(self) -> dict[str, Any]:
        return requests.get(self.tool_url + "/lti/jwks.json", timeout=10).json()

    def _token(self, request: Request) -> Response:
        assertion = request.form["client_assertion"]
        kid = jwt.get_unverified_header(assertion)["kid"]
        jwk = next(k for k in self._tool_keys()["keys"] if k["kid"] == kid)
        jwt.decode(assertion, jwt.PyJWK(jwk).key, algorithms=["RS256"], audience=self.url + "/token")
        return Response(json.dumps({"access_token": "token-" + uuid.uuid4().hex, "token_type": "Bearer",
                                    "expires_in": 3600}), content_type="application/json")

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
        token = request.form["JWT"]
        kid = jwt.get_unverified_header(token)["kid"]
        jwk = next(k for k in self._tool_keys()["keys"] if k["kid"] == kid)
        self.deep_link_returns.append(jwt.decode(token, jwt.PyJWK(jwk).key, algorithms=["RS256"],
                                                 audience=self.issuer))
        return Response("<p id='placed'>Placed in the course.</p>", content_type="text/html")

    def _course(self, request: Request) -> Response:
        """An LMS course page framing the tool's launch for login_hint."""
        params = {"iss": self.issuer, "login_hint": request.args["login_hint"], "client_id": self.client_id,
                  "lti_deployment_id": self.deployment_id, "target_link_uri": self.tool_url + "/lti/launch"}
        tool = html.escape(request.args.get("tool", self.tool_url) + "/lti/login?" + urlencode(params))
        page = ('<!doctype html><meta name="viewport" content="width=device-width, initial-scale=1">'
                '<title>LMS course</title><h1>LMS course</h1>'
                f'<iframe id="tool" src="{tool}" style="width:100%;height:900px;border:1px solid #888" '
                'allow="fullscreen"></iframe>')
        return Response(page, content_type="text/html")
