"""Registered platforms: an admin adds an LMS (issuer, client id, deployment ids, its endpoints); what the LMS's
admin pastes on their side; and the origins allowed to frame Telelab's pages, read by every worker.

The framing origins are cached per process and dropped when any worker announces a change (topic `lti`).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass
from urllib.parse import urlsplit

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import Engine, delete, select
from sqlalchemy.orm import Session

from middleware import events
from middleware.errors import Refused, written_number
from middleware.i18n import N_
from middleware.models.lti import LtiDeployment, LtiPlatform

EVENT_TOPIC = "lti"
_LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")
MAX_DEPLOYMENTS = 50
ORIGINS_TTL_S = 60.0
# The fields as a refusal names them (marked here, said in the request's language).
_ISSUER = N_("the issuer")
_LOGIN_URL = N_("the login (authorization) URL")
_TOKEN_URL = N_("the access-token URL")
_KEY_SET_URL = N_("the key-set (JWKS) URL")


class InvalidPlatform(Refused):
    """A registration field that is missing or wrong, named."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(400, "invalid_field", message, field)


def _capital(text: str) -> str:
    return text[:1].upper() + text[1:]


def _text(fields: Mapping[str, object], name: str, label: str, limit: int = 255) -> str:
    value = fields.get(name)
    if not isinstance(value, str) or not value.strip():
        raise InvalidPlatform(name, gettext("Fill in %(label)s.", label=gettext(label)))
    value = value.strip()
    if len(value) > limit:
        raise InvalidPlatform(name, gettext("%(label)s is at most %(limit)s characters.",
                                            label=_capital(gettext(label)), limit=written_number(limit)))
    return value


def clean_url(value: str, field: str, label: str, **names: str) -> str:
    """An https URL (http only for this machine, when testing), with a host; label is a marked message (N_) that
    names the field, filled with names."""
    said = _capital(gettext(label, **names))
    parts = urlsplit(value)
    if parts.scheme not in ("https", "http") or not parts.hostname:
        raise InvalidPlatform(field, gettext("%(label)s must be a full address starting with https://.", label=said))
    if parts.scheme == "http" and parts.hostname not in _LOCAL_HOSTS:
        raise InvalidPlatform(field, gettext("%(label)s must use https:// (plain http only for 127.0.0.1).",
                                             label=said))
    if any(ch.isspace() for ch in value):
        raise InvalidPlatform(field, gettext("%(label)s must not contain spaces.", label=said))
    return value


def origin_of(url: str) -> str:
    """scheme://host[:port] of url."""
    parts = urlsplit(url)
    return f"{parts.scheme}://{parts.netloc}".lower()


def _list(value: object) -> list[str]:
    if isinstance(value, list):
        items = [str(item) for item in value]
    elif isinstance(value, str):
        items = value.replace(",", "\n").splitlines()
    else:
        items = []
    return [item.strip() for item in items if item.strip()]


@dataclass(frozen=True)
class PlatformFields:
    """A registration's checked fields."""

    name: str
    issuer: str
    client_id: str
    auth_login_url: str
    auth_token_url: str
    key_set_url: str
    deployment_ids: list[str]
    frame_origins: list[str]


def clean_platform(fields: Mapping[str, object]) -> PlatformFields:
    """Every field checked, the first wrong one named."""
    issuer = clean_url(_text(fields, "issuer", _ISSUER), "issuer", _ISSUER)
    client_id = _text(fields, "client_id", N_("the client id"))
    login = clean_url(_text(fields, "auth_login_url", _LOGIN_URL, 1000), "auth_login_url", _LOGIN_URL)
    token = clean_url(_text(fields, "auth_token_url", _TOKEN_URL, 1000), "auth_token_url", _TOKEN_URL)
    key_set = clean_url(_text(fields, "key_set_url", _KEY_SET_URL, 1000), "key_set_url", _KEY_SET_URL)
    deployments = _list(fields.get("deployment_ids"))
    if not deployments:
        raise InvalidPlatform("deployment_ids", gettext("Give at least one deployment id (the LMS shows it once "
                                                        "the tool is added)."))
    if len(deployments) > MAX_DEPLOYMENTS or any(len(d) > 255 for d in deployments):
        raise InvalidPlatform("deployment_ids", gettext("Give at most %(count)s deployment ids of at most "
                                                        "%(limit)s characters each.",
                                                        count=written_number(MAX_DEPLOYMENTS),
                                                        limit=written_number(255)))
    origins = [origin_of(clean_url(o, "frame_origins", N_("the page origin %(origin)s"), origin=repr(o)))
               for o in _list(fields.get("frame_origins"))]
    name = fields.get("name")
    title = name.strip()[:200] if isinstance(name, str) and name.strip() else urlsplit(issuer).hostname or issuer
    return PlatformFields(title, issuer, client_id, login, token, key_set, list(dict.fromkeys(deployments)),
                          list(dict.fromkeys([origin_of(issuer), *origins])))


def register(session: Session, fields: Mapping[str, object]) -> LtiPlatform:
    """Adds a platform, or updates the one with the same issuer and client id (its deployments replaced)."""
    clean = clean_platform(fields)
    platform = session.scalar(select(LtiPlatform).where(LtiPlatform.issuer == clean.issuer,
                                                        LtiPlatform.client_id == clean.client_id))
    if platform is None:
        platform = LtiPlatform(issuer=clean.issuer, client_id=clean.client_id)
        session.add(platform)
    platform.name, platform.auth_login_url, platform.auth_token_url = clean.name, clean.auth_login_url, \
        clean.auth_token_url
    platform.key_set_url, platform.frame_origins = clean.key_set_url, clean.frame_origins
    session.flush()
    session.execute(delete(LtiDeployment).where(LtiDeployment.platform_id == platform.id))
    session.add_all(LtiDeployment(platform_id=platform.id, deployment_id=d) for d in clean.deployment_ids)
    session.flush()
    events.announce(session, EVENT_TOPIC, "platforms")
    return platform


def remove(session: Session, platform_id: int) -> None:
    """Removes a platform: its launches stop working; accounts and courses it made stay."""
    platform = session.get(LtiPlatform, platform_id)
    if platform is None:
        raise Refused(404, "unknown_platform", gettext("There is no such platform."), "platform_id")
    session.delete(platform)
    session.flush()
    events.announce(session, EVENT_TOPIC, "platforms")


def listed(session: Session) -> list[tuple[LtiPlatform, list[str]]]:
    """Every platform with its deployment ids, by name."""
    platforms = list(session.scalars(select(LtiPlatform).order_by(LtiPlatform.name, LtiPlatform.id)))
    deployments: dict[int, list[str]] = {}
    for platform_id, deployment in session.execute(select(LtiDeployment.platform_id, LtiDeployment.deployment_id)
                                                   .order_by(LtiDeployment.id)):
        deployments.setdefault(platform_id, []).append(deployment)
    return [(p, deployments.get(p.id, [])) for p in platforms]


def tool_urls(base_url: str) -> dict[str, str]:
    """What the LMS's administrator pastes on their side, for this site's address."""
    base = base_url.rstrip("/")
    return {"tool_url": base + "/", "login_url": base + "/lti/login", "launch_url": base + "/lti/launch",
            "redirect_urls": base + "/lti/launch", "deep_link_url": base + "/lti/launch",
            "jwks_url": base + "/lti/jwks.json"}


class FrameOrigins:
    """The registered platforms' framing origins, cached per process; a change in any worker drops the cache."""

    def __init__(self, engine: Engine) -> None:
        self._engine = engine
        self._lock = threading.Lock()
        self._origins: tuple[str, ...] | None = None
        self._read_at = 0.0
        events.listen(engine, EVENT_TOPIC, lambda _key: self.forget())

    def forget(self) -> None:
        """Read them again next time."""
        with self._lock:
            self._origins = None

    def get(self) -> tuple[str, ...]:
        """Every registered platform's framing origins (empty: no platform, frames refused)."""
        with self._lock:
            if self._origins is not None and time.monotonic() - self._read_at < ORIGINS_TTL_S:
                return self._origins
        try:
            with Session(self._engine) as session:
                rows = session.scalars(select(LtiPlatform.frame_origins))
                found = tuple(sorted({o for origins in rows for o in origins or ()}))
        except Exception:  # noqa: BLE001 - an unmigrated database (telelab db upgrade) frames nothing
            found = ()
        with self._lock:
            self._origins, self._read_at = found, time.monotonic()
        return found
