"""pylti1p3 backed by the database: registrations and deployments from the registered platforms, and its launch
store (nonces, states, validated launches) in a table every worker shares.

A nonce is handed out at the OIDC login and taken back once at the launch: check_value deletes it, so the same
id token posted again is refused ("replayed") in whichever worker it reaches.
"""

from __future__ import annotations

from datetime import timedelta
from typing import Any

from pylti1p3.deployment import Deployment
from pylti1p3.launch_data_storage.base import LaunchDataStorage
from pylti1p3.registration import Registration
from pylti1p3.tool_config import ToolConfAbstract
from sqlalchemy import delete, select
from sqlalchemy.orm import Session

from middleware.lti import keys
from middleware.models.accounts import as_utc, utc_now
from middleware.models.lti import LtiDeployment, LtiLaunchValue, LtiPlatform

DEFAULT_LIFETIME_S = 3600


class ToolRegistration(Registration):
    """A pylti1p3 registration whose kid is the tool key's own (so a rotated key is named as the JWKS names it)."""

    def __init__(self, kid: str) -> None:
        super().__init__()
        self._kid = kid

    def get_kid(self) -> str:
        """The signing key's id."""
        return self._kid


class DatabaseToolConf(ToolConfAbstract):
    """Registrations of the platforms registered in the database; one issuer may hold several client ids."""

    def __init__(self, session: Session) -> None:
        super().__init__()
        self._session = session
        self.issuers_relation_types = {}

    def check_iss_has_one_client(self, iss: str) -> bool:
        """Never: every issuer is looked up with its client id."""
        return False

    def check_iss_has_many_clients(self, iss: str) -> bool:
        """Always (see check_iss_has_one_client)."""
        return True

    def platform(self, iss: str, client_id: str | None) -> LtiPlatform | None:
        """The registered platform for iss and client_id (or iss alone when it has exactly one)."""
        query = select(LtiPlatform).where(LtiPlatform.issuer == iss)
        if client_id:
            query = query.where(LtiPlatform.client_id == client_id)
        found = list(self._session.scalars(query.limit(2)))
        return found[0] if len(found) == 1 else None

    def issuer_known(self, iss: str) -> bool:
        """True when some platform registered iss."""
        return self._session.scalar(select(LtiPlatform.id).where(LtiPlatform.issuer == iss).limit(1)) is not None

    def _registration(self, platform: LtiPlatform | None) -> Registration | None:
        if platform is None:
            return None
        key = keys.signing_key(self._session)
        registration = ToolRegistration(key.kid)
        registration.set_issuer(platform.issuer).set_client_id(platform.client_id) \
            .set_auth_login_url(platform.auth_login_url).set_auth_token_url(platform.auth_token_url) \
            .set_key_set_url(platform.key_set_url).set_tool_private_key(key.private_pem) \
            .set_tool_public_key(key.public_pem)
        return registration

    def find_registration_by_issuer(self, iss: str, *args: Any, **kwargs: Any) -> Registration:
        """The registration of iss when it has one client id."""
        return self._registration(self.platform(iss, None))  # type: ignore[return-value]

    def find_registration_by_params(self, iss: str, client_id: str, *args: Any, **kwargs: Any) -> Registration:
        """The registration of iss and client_id (None: not registered)."""
        return self._registration(self.platform(iss, client_id or None))  # type: ignore[return-value]

    def find_deployment(self, iss: str, deployment_id: str) -> Deployment | None:
        """The deployment of iss's only registration."""
        return self.find_deployment_by_params(iss, deployment_id, "")

    def find_deployment_by_params(self, iss: str, deployment_id: str, client_id: str, *args: Any,
                                  **kwargs: Any) -> Deployment | None:
        """The deployment when the platform registered it."""
        platform = self.platform(iss, client_id or None)
        if platform is None or not isinstance(deployment_id, str):
            return None
        known = self._session.scalar(select(LtiDeployment.id).where(
            LtiDeployment.platform_id == platform.id, LtiDeployment.deployment_id == deployment_id))
        return Deployment().set_deployment_id(deployment_id) if known is not None else None


class DatabaseLaunchStorage(LaunchDataStorage[Any]):
    """pylti1p3's launch store in the lti_launch_values table (the request's session: one unit of work)."""

    def __init__(self, session: Session) -> None:
        super().__init__()
        self._session = session

    def get_session_cookie_name(self) -> str | None:
        """None: keys are not prefixed by a cookie (the state cookie still binds a launch to its browser)."""
        return None

    def can_set_keys_expiration(self) -> bool:
        """Keys expire."""
        return True

    def get_value(self, key: str) -> Any:
        """The value under key, None when missing or expired."""
        row = self._session.get(LtiLaunchValue, self._prepare_key(key)[:255])
        if row is None or as_utc(row.expires_at) <= utc_now():
            return None
        return row.value

    def set_value(self, key: str, value: Any, exp: int | None = None) -> None:
        """Stores value under key for exp seconds."""
        name = self._prepare_key(key)[:255]
        expires = utc_now() + timedelta(seconds=exp or DEFAULT_LIFETIME_S)
        row = self._session.get(LtiLaunchValue, name)
        if row is None:
            self._session.add(LtiLaunchValue(key=name, value=value, expires_at=expires))
        else:
            row.value, row.expires_at = value, expires
        self._session.flush()

    def check_value(self, key: str) -> bool:
        """Takes the key away (a nonce is good once): True when it was there and fresh."""
        name = self._prepare_key(key)[:255]
        taken = self._session.execute(delete(LtiLaunchValue).where(
            LtiLaunchValue.key == name, LtiLaunchValue.expires_at > utc_now()))
        return bool(taken.rowcount)  # type: ignore[attr-defined]


def forget_expired(session: Session) -> int:
    """Deletes expired launch values; the number deleted."""
    result = session.execute(delete(LtiLaunchValue).where(LtiLaunchValue.expires_at <= utc_now()))
    return int(result.rowcount)  # type: ignore[attr-defined]
