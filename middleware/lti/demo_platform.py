"""The platform's half of LTI 1.3, for stand-in LMSs: the demo LMS of `make run` (`demo_lms.py`) and the test LMS
(`tests/integration/lti/platform.py`). No real LMS uses it, and Telelab's own checks never do: a launch is checked
by pylti1p3 whoever signed it.

A `PlatformSide` holds its RSA key (and key set), writes a launch's claims and signs them, answers the OIDC
authorization request with a page that posts the launch back to the tool, checks a tool's signed request for a
service token against the tool's own key set, and reads a tool's deep-linking answer the same way.
"""

from __future__ import annotations

import html
import json
import time
import uuid
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import urlencode

import jwt
import requests
from jwcrypto.jwk import JWK  # type: ignore[import-untyped]

CLAIM = "https://purl.imsglobal.org/spec/lti/claim/"
LEARNER = "http://purl.imsglobal.org/vocab/lis/v2/membership#Learner"
INSTRUCTOR = "http://purl.imsglobal.org/vocab/lis/v2/membership#Instructor"
LMS_ADMIN = "http://purl.imsglobal.org/vocab/lis/v2/institution/person#Administrator"
SCORE_SCOPE = "https://purl.imsglobal.org/spec/lti-ags/scope/score"
LINEITEM_SCOPE = "https://purl.imsglobal.org/spec/lti-ags/scope/lineitem"
NRPS_CLAIM = "https://purl.imsglobal.org/spec/lti-nrps/claim/namesroleservice"
AGS_CLAIM = "https://purl.imsglobal.org/spec/lti-ags/claim/endpoint"
DEEP_LINKING_CLAIM = "https://purl.imsglobal.org/spec/lti-dl/claim/deep_linking_settings"
CONTENT_ITEMS_CLAIM = "https://purl.imsglobal.org/spec/lti-dl/claim/content_items"
TOKEN_LIFETIME_S = 300
HTTP_TIMEOUT_S = 10


def new_key() -> tuple[str, dict[str, Any]]:
    """(private PEM, public JWK with kid) of a fresh RSA key."""
    key = JWK.generate(kty="RSA", size=2048)
    public = json.loads(key.export_public())
    public.update({"kid": key.thumbprint(), "alg": "RS256", "use": "sig"})
    return key.export_to_pem(private_key=True, password=None).decode(), public


def registration(name: str, url: str, client_id: str, deployment_id: str) -> dict[str, str]:
    """What the tool's admin enters for a stand-in LMS at url (its issuer; its endpoints are under it)."""
    return {"name": name, "issuer": url, "client_id": client_id, "deployment_ids": deployment_id,
            "auth_login_url": url + "/auth", "auth_token_url": url + "/token", "key_set_url": url + "/jwks"}


@dataclass(frozen=True)
class LmsCourse:
    """The LMS course a launch comes from (its context claim)."""

    id: str
    label: str
    title: str


@dataclass
class PlatformSide:
    """A stand-in LMS's LTI side: issuer = url (its own origin); client_id and deployment_id given to the tool."""

    url: str
    tool_url: str
    client_id: str
    deployment_id: str
    private_pem: str = ""
    public_jwk: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.private_pem:
            self.private_pem, self.public_jwk = new_key()

    @property
    def issuer(self) -> str:
        """The issuer (the LMS's own origin)."""
        return self.url

    def registration(self, name: str) -> dict[str, str]:
        """What the tool's admin enters for this LMS."""
        return registration(name, self.url, self.client_id, self.deployment_id)

    def key_set(self) -> dict[str, Any]:
        """The LMS's public key set (served at /jwks)."""
        return {"keys": [self.public_jwk]}

    def login_url(self, login_hint: str, message_hint: str | None = None) -> str:
        """The tool's OIDC login initiation for login_hint, as the LMS's page opens it."""
        params = {"iss": self.issuer, "login_hint": login_hint, "client_id": self.client_id,
                  "lti_deployment_id": self.deployment_id, "target_link_uri": self.tool_url + "/lti/launch"}
        if message_hint is not None:
            params["lti_message_hint"] = message_hint
        return self.tool_url + "/lti/login?" + urlencode(params)

    def claims(self, nonce: str, sub: str, roles: list[str], *, course: LmsCourse | None,
               custom: dict[str, str] | None = None, lineitem: str | None = None, deep_link: bool = False,
               locale: str | None = None, resource_link: str | None = None, **extra: Any) -> dict[str, Any]:
        """A launch's claims for the tool (names and role, grade and deep-linking services at the LMS's URLs)."""
        now = int(time.time())
        body: dict[str, Any] = {
            "iss": self.issuer, "aud": self.client_id, "sub": sub, "nonce": nonce, "iat": now,
            "exp": now + TOKEN_LIFETIME_S, "given_name": sub.split("-")[0], "name": sub,
            CLAIM + "deployment_id": self.deployment_id, CLAIM + "version": "1.3.0", CLAIM + "roles": roles,
            CLAIM + "message_type": "LtiDeepLinkingRequest" if deep_link else "LtiResourceLinkRequest",
            CLAIM + "target_link_uri": self.tool_url + "/lti/launch",
            NRPS_CLAIM: {"context_memberships_url": self.url + "/memberships", "service_versions": ["2.0"]},
            AGS_CLAIM: {"scope": [SCORE_SCOPE, LINEITEM_SCOPE], "lineitems": self.url + "/lineitems",
                        **({"lineitem": lineitem} if lineitem else {})},
        }
        if locale:
            body[CLAIM + "launch_presentation"] = {"locale": locale}
        if course is not None:
            body[CLAIM + "context"] = {"id": course.id, "label": course.label, "title": course.title}
        if deep_link:
            body[DEEP_LINKING_CLAIM] = {
                "deep_link_return_url": self.url + "/deep-link-return", "accept_types": ["ltiResourceLink"],
                "accept_presentation_document_targets": ["iframe", "window"], "accept_multiple": True}
        else:
            body[CLAIM + "resource_link"] = {"id": resource_link or "link-" + (custom or {}).get("telelab_target",
                                                                                                 "home")}
        if custom:
            body[CLAIM + "custom"] = custom
        body.update(extra)
        return body

    def sign(self, claims: dict[str, Any], key: str | None = None, kid: str | None = None) -> str:
        """claims signed with the platform's key (or another)."""
        return jwt.encode(claims, key or self.private_pem, algorithm="RS256",
                          headers={"kid": kid or self.public_jwk["kid"]})

    def launch_page(self, redirect_uri: str, state: str, claims: dict[str, Any]) -> str:
        """The OIDC authorization endpoint's answer: a page that posts the signed launch to the tool at once."""
        fields = {"id_token": self.sign(claims), "state": state}
        inputs = "".join(f'<input type="hidden" name="{k}" value="{html.escape(v)}">' for k, v in fields.items())
        return (f'<!doctype html><title>LMS</title><form id="f" method="post" action="{html.escape(redirect_uri)}">'
                f'{inputs}<button>Go</button></form><script>document.getElementById("f").submit()</script>')

    def _tool_key(self, token: str) -> Any:
        kid = jwt.get_unverified_header(token)["kid"]
        keys = requests.get(self.tool_url + "/lti/jwks.json", timeout=HTTP_TIMEOUT_S).json()["keys"]
        return jwt.PyJWK(next(k for k in keys if k["kid"] == kid)).key

    def access_token(self, assertion: str) -> dict[str, Any]:
        """The answer to a tool's service-token request, once its signed assertion checks against the tool's keys
        (jwt.PyJWTError, StopIteration or requests' errors otherwise)."""
        jwt.decode(assertion, self._tool_key(assertion), algorithms=["RS256"], audience=self.url + "/token")
        return {"access_token": "token-" + uuid.uuid4().hex, "token_type": "Bearer", "expires_in": 3600}

    def deep_link_answer(self, token: str) -> dict[str, Any]:
        """The claims of a tool's deep-linking answer, checked against the tool's keys."""
        return dict(jwt.decode(token, self._tool_key(token), algorithms=["RS256"], audience=self.issuer))
