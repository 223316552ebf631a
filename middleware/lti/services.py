"""pylti1p3 for the services outside a launch (grades, rosters): a registration from the database and a
connector that asks the platform for an access token signed with the tool's key."""

from __future__ import annotations

import re

import requests
from flask_babel import gettext  # type: ignore[import-untyped]
from pylti1p3.registration import Registration
from pylti1p3.service_connector import ServiceConnector
from sqlalchemy.orm import Session

from middleware.i18n import N_
from middleware.lti.tool_conf import DatabaseToolConf
from middleware.models.lti import LtiPlatform

HTTP_TIMEOUT_S = 15.0


class _TimeoutSession(requests.Session):
    """A requests session whose calls never wait for ever on an LMS."""

    def request(self, *args, **kwargs):
        """requests.Session.request with a timeout when none is given."""
        kwargs.setdefault("timeout", HTTP_TIMEOUT_S)
        return super().request(*args, **kwargs)


def http_session() -> requests.Session:
    """The HTTP client every call to an LMS goes through."""
    session = _TimeoutSession()
    session.headers["User-Agent"] = "Telelab-LTI"
    return session


def registration_of(session: Session, platform: LtiPlatform) -> Registration:
    """pylti1p3's registration of platform, signed with the current tool key."""
    registration = DatabaseToolConf(session).find_registration_by_params(platform.issuer, platform.client_id)
    assert registration is not None
    return registration


def connector(session: Session, platform: LtiPlatform, http: requests.Session | None = None) -> ServiceConnector:
    """A service connector for platform."""
    return ServiceConnector(registration_of(session, platform), http or http_session())


def lms_answer(error: Exception) -> str | None:
    """What the LMS answered (its status and text), or why it could not be reached, in English (it is stored: `said`
    says it in the reader's language); None for an error of another kind."""
    response = getattr(error, "response", None)
    if isinstance(response, requests.Response):
        body = " ".join(response.text.split())[:200]
        return f"The LMS answered {response.status_code} {response.reason or ''}".rstrip() + \
            (f": {body}" if body else ".")
    if isinstance(error, requests.RequestException):
        return f"The LMS could not be reached ({type(error).__name__})."
    return None


def failure_reason(error: Exception) -> str:
    """Why a grade was not sent, in English (stored with the grade; `said` says it in the reader's language)."""
    return lms_answer(error) or f"The grade could not be sent: {str(error)[:200]}"


# The stored sentences above, and the messages that say them in the reader's language (the LMS's own text stays).
_STORED = (
    (re.compile(r"The LMS answered (?P<status>\d{3}[^:]*): (?P<answer>.*)", re.DOTALL),
     N_("The LMS answered %(status)s: %(answer)s")),
    (re.compile(r"The LMS answered (?P<status>\d{3}[^:]*)\."), N_("The LMS answered %(status)s.")),
    (re.compile(r"The LMS could not be reached \((?P<kind>\w+)\)\."), N_("The LMS could not be reached (%(kind)s).")),
    (re.compile(r"The grade could not be sent: (?P<reason>.*)", re.DOTALL),
     N_("The grade could not be sent: %(reason)s")),
)


def said(text: str) -> str:
    """A stored reason of lms_answer or failure_reason in the request's language (English outside a request)."""
    for pattern, message in _STORED:
        if match := pattern.fullmatch(text):
            values = {name: str(gettext(value)) if name == "reason" else value
                      for name, value in match.groupdict().items()}  # a reason of Telelab's own is in the catalogue
            return str(gettext(message, **values))
    return str(gettext(text))
