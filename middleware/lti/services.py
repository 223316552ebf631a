"""pylti1p3 for the services outside a launch (grades, rosters): a registration from the database and a
connector that asks the platform for an access token signed with the tool's key."""

from __future__ import annotations

import requests
from pylti1p3.registration import Registration
from pylti1p3.service_connector import ServiceConnector
from sqlalchemy.orm import Session

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


def failure_reason(error: Exception) -> str:
    """A sentence a tutor reads: what the LMS answered, or why it could not be reached."""
    response = getattr(error, "response", None)
    if isinstance(response, requests.Response):
        body = " ".join(response.text.split())[:200]
        return f"The LMS answered {response.status_code} {response.reason or ''}".rstrip() + \
            (f": {body}" if body else ".")
    if isinstance(error, requests.RequestException):
        return f"The LMS could not be reached ({type(error).__name__})."
    return f"The grade could not be sent: {str(error)[:200]}"
