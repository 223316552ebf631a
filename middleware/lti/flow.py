"""The OIDC login and the launch, through pylti1p3's Flask adapter, with every refusal as a sentence.

A refused launch raises LaunchRefused: the request's unit of work is discarded, so nothing it made stays.
"""

from __future__ import annotations

import re
from typing import Any, cast

import jwt
from flask import Response, request
from flask_babel import gettext  # type: ignore[import-untyped]
from pylti1p3.contrib.flask import FlaskMessageLaunch, FlaskOIDCLogin, FlaskRequest
from pylti1p3.deep_link_resource import DeepLinkResource
from pylti1p3.exception import LtiException, OIDCException
from pylti1p3.lineitem import LineItem
from pylti1p3.message_launch import MessageLaunch
from sqlalchemy.orm import Session

from middleware.i18n import N_
from middleware.lti import launches
from middleware.lti.launches import LaunchRefused
from middleware.lti.services import http_session
from middleware.lti.tool_conf import DatabaseLaunchStorage, DatabaseToolConf
from middleware.models.lti import LtiPlatform

LAUNCH_LIFETIME_S = 3600
_CLAIM_NAMED = re.compile(r'"([A-Za-z0-9_:/.#-]{1,200})" claim')
# The claims a launch must carry (PyJWT refuses a token without them before its signature is trusted).
REQUIRED_CLAIMS = ["exp", "iat", "iss", "aud", "sub", "nonce"]

# pylti1p3's messages -> (code, sentence a person reads: marked for the catalogue, said in the request's language).
_REFUSALS = (
    ("Missing state", "no_state", N_("The launch came without its state. Start it again from the LMS.")),
    ("State not found", "cookies_blocked",
     N_("Your browser did not send back Telelab's cookie from the LMS's frame (third-party cookies may be blocked). "
        "Open the activity in a new window from the LMS, or allow cookies for this site.")),
    ("Invalid Nonce", "replayed",
     N_("This launch was already used (its nonce is spent). Start it again from the LMS.")),
    ('"nonce" is empty', "missing_claims", N_("The launch has no nonce claim; the LMS must send one.")),
    ("Registration not found", "unknown_platform",
     N_("This LMS (its issuer and client id) is not registered with Telelab. Ask the lab's administrator to "
        "register it.")),
    ("Client id not registered", "wrong_audience",
     N_("This launch was meant for another tool (its audience is not Telelab's client id).")),
    ("Signature has expired", "expired", N_("The launch has expired. Start it again from the LMS.")),
    ("Token is missing the", "missing_claims", N_("The launch lacks a required claim (%(detail)s).")),
    ("Can't decode id_token", "bad_signature",
     N_("The launch's signature does not match the LMS's keys, so it cannot be trusted.")),
    ("Unable to find public key", "bad_signature",
     N_("The launch was signed with a key the LMS does not publish, so it cannot be trusted.")),
    ("JWT KID not found", "bad_signature", N_("The launch names no signing key, so it cannot be trusted.")),
    ("Unable to find deployment", "unknown_deployment",
     N_("This deployment of Telelab in the LMS is not registered. Ask the lab's administrator to add its "
        "deployment id.")),
    ("deployment_id is not set", "missing_claims", N_("The launch names no deployment.")),
    ("Invalid id_token", "bad_token", N_("The launch's token is not a signed JWT.")),
    ("Invalid JWT format", "bad_token", N_("The launch's token cannot be read.")),
    ("Missing id_token", "bad_token", N_("The launch came without its token.")),
    ("Error during fetch", "platform_keys_unreachable",
     N_("The LMS's key set could not be fetched, so the launch cannot be checked. Try again in a moment.")),
    ("Must have a user", "missing_claims", N_("The launch names no person (sub).")),
    ("Incorrect version", "missing_claims", N_("The launch is not LTI 1.3.0.")),
    ("Missing Roles", "missing_claims", N_("The launch names no roles.")),
    ("Missing Resource Link", "missing_claims", N_("The launch names no resource link.")),
    ("Missing Deep Linking", "missing_claims", N_("The deep-linking launch lacks its settings.")),
    ("Must support", "missing_claims", N_("The deep-linking launch does not accept resource links.")),
    ('"iss" is empty', "missing_claims", N_("The launch names no issuer.")),
    ("message type", "missing_claims", N_("The launch's message type is missing or unknown.")),
    ("Message validation failed", "missing_claims", N_("The launch's message is incomplete.")),
)


def refusal(error: Exception) -> LaunchRefused:
    """The sentence for a pylti1p3 refusal."""
    text = str(error)
    for marker, code, sentence in _REFUSALS:
        if marker in text:
            named = _CLAIM_NAMED.search(text)  # PyJWT: 'Token is missing the "sub" claim'
            detail = named.group(1) if named else ""
            return LaunchRefused(code, gettext(sentence, detail=detail or gettext("a claim")),
                                 status=401 if code in ("bad_signature", "expired", "replayed") else 400)
    return LaunchRefused("refused", gettext("The launch could not be checked: %(reason)s", reason=text[:200]))


def _request(params: dict[str, str] | None = None) -> FlaskRequest:
    return FlaskRequest(request_data=params) if params else FlaskRequest()


def login_redirect(session: Session, launch_url: str, params: dict[str, str] | None = None) -> Response:
    """The redirect to the platform's authorization endpoint (state cookie set, nonce stored)."""
    storage = DatabaseLaunchStorage(session)
    login = FlaskOIDCLogin(_request(params), DatabaseToolConf(session), launch_data_storage=storage)
    try:
        return login.redirect(launch_url)
    except (OIDCException, LtiException) as error:
        raise LaunchRefused("bad_login", gettext("The LMS's login request was refused: %(reason)s. Check the "
                                                 "platform's registration.", reason=str(error)[:200])) from None


class ValidatedLaunch:
    """A checked launch: its claims, its registered platform and its id (to find it again for deep linking)."""

    def __init__(self, launch: FlaskMessageLaunch, claims: dict[str, Any], platform: LtiPlatform) -> None:
        self.launch, self.claims, self.platform = launch, claims, platform

    @property
    def launch_id(self) -> str:
        """The id the launch is stored under."""
        return str(self.launch.get_launch_id())

    @property
    def is_deep_link(self) -> bool:
        """A deep-linking request (a tutor placing content)."""
        return bool(self.launch.is_deep_link_launch())


def validate_launch(session: Session) -> ValidatedLaunch:
    """The launch of this request, every check made (state, nonce once, registration, signature, expiry,
    audience, deployment, message), or LaunchRefused."""
    tool_conf = DatabaseToolConf(session)
    launch = FlaskMessageLaunch(FlaskRequest(), tool_conf, launch_data_storage=DatabaseLaunchStorage(session),
                                requests_session=http_session())
    launch.set_jwt_verify_options(cast(dict[str, bool], {"verify_aud": False, "require": REQUIRED_CLAIMS}))
    launch.set_launch_data_lifetime(LAUNCH_LIFETIME_S)
    try:
        claims = dict(launch.get_launch_data())
    except (LtiException, ValueError, TypeError, KeyError) as error:
        refused = refusal(error)
        if refused.code == "unknown_platform" and tool_conf.issuer_known(_unverified_issuer()):
            refused = LaunchRefused("wrong_audience", gettext("This launch was meant for another tool (its "
                                                              "audience is not a client id this LMS registered "
                                                              "for Telelab)."))
        raise refused from None
    platform = tool_conf.platform(str(claims.get("iss")), launch.get_client_id())
    if platform is None:
        raise LaunchRefused("unknown_platform", gettext("This LMS is not registered with Telelab."))
    launches.check_audience(claims, platform.client_id)
    return ValidatedLaunch(launch, claims, platform)


def _unverified_issuer() -> str:
    """The issuer the posted token claims (unverified: only to word a refusal)."""
    token = request.form.get("id_token", "")
    try:
        return str(jwt.decode(token, options={"verify_signature": False}).get("iss", ""))
    except jwt.PyJWTError:
        return ""


def restore_launch(session: Session, launch_id: str) -> MessageLaunch:
    """A stored launch (a deep-linking request being answered)."""
    try:
        return FlaskMessageLaunch.from_cache(launch_id, FlaskRequest(), DatabaseToolConf(session),
                                             launch_data_storage=DatabaseLaunchStorage(session))
    except LtiException:
        raise LaunchRefused("launch_expired", gettext("This placement has expired. Choose \"Select content\" in "
                                                      "the LMS again.")) from None


def launch_platform(session: Session, launch: MessageLaunch) -> LtiPlatform:
    """The registered platform of a restored launch (refused when it was removed meanwhile)."""
    platform = DatabaseToolConf(session).platform(str(launch.get_launch_data().get("iss")), launch.get_client_id())
    if platform is None:
        raise LaunchRefused("unknown_platform", gettext("This LMS is not registered with Telelab."))
    return platform


# What runs only in a window of its own: a Python exercise needs cross-origin isolation, which no LMS's frame gives.
OWN_WINDOW_KINDS = ("exercise:",)


class _Resource(DeepLinkResource):
    """pylti1p3's resource link, with the target it keeps but does not send: "window" asks the LMS to open it in a
    window (or tab) of its own (LTI Deep Linking 2.0, the content item's window property)."""

    def to_dict(self) -> dict[str, object]:
        item = super().to_dict()
        if self._target == "window":
            item["window"] = {"targetName": "_blank"}
        return item


def deep_link_response(launch: MessageLaunch, items: list[tuple[str, str, str, float | None]],
                       secret: str) -> tuple[str, str]:
    """(the platform's return URL, the signed JWT) placing items: (title, url, target, score maximum or None)."""
    context = cast(dict[str, Any], launch.get_launch_data().get(launches.CONTEXT_CLAIM) or {})
    resources = []
    for title, url, target, maximum in items:
        resource = _Resource().set_url(url).set_title(title).set_custom_params(
            {launches.TARGET_PARAM: target, launches.SIGNATURE_PARAM: launches.sign_target(
                secret, str(context.get("id", "")), target)})
        if target.startswith(OWN_WINDOW_KINDS):
            resource.set_target("window")
        if maximum is not None:
            resource.set_lineitem(LineItem().set_label(title).set_score_maximum(maximum).set_tag(target)
                                  .set_resource_id(target))
        resources.append(resource)
    deep_link = launch.get_deep_link()
    return deep_link._deep_link_settings["deep_link_return_url"], deep_link.get_response_jwt(resources)

