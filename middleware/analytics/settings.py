"""Where xAPI statements go: the Learning Record Store's endpoint and credentials, and the lab's address that every
statement's activities and accounts start with. Read from app.config, else from the TELELAB_ environment; a wrong
value stops the start with a sentence naming the setting."""

from __future__ import annotations

import os
from dataclasses import dataclass
from urllib.parse import urlsplit

from flask import Flask

from middleware.config import ConfigError


@dataclass(frozen=True)
class XapiSettings:
    """The xAPI settings create_app was given; lrs_url None: no LRS, statements are only exported."""

    lrs_url: str | None
    username: str
    password: str
    homepage: str | None
    interval_s: float

    @property
    def sends(self) -> bool:
        """Whether statements go to an LRS."""
        return self.lrs_url is not None


def _http_url(value: str, env: str) -> str:
    parts = urlsplit(value)
    if parts.scheme not in ("http", "https") or not parts.netloc or any(c.isspace() for c in value):
        raise ConfigError(f"{env} must be an http(s) address such as https://lrs.example.edu/xapi/, not {value!r}.")
    return value


def _setting(app: Flask, key: str, env: str, default: str = "") -> str:
    return str(app.config.get(key, os.environ.get(env, default))).strip()


def load(app: Flask) -> XapiSettings:
    """The app's xAPI settings."""
    lrs = _setting(app, "XAPI_LRS_URL", "TELELAB_XAPI_LRS_URL")
    homepage = _setting(app, "XAPI_HOMEPAGE", "TELELAB_XAPI_HOMEPAGE")
    raw_interval = _setting(app, "XAPI_SEND_INTERVAL_S", "TELELAB_XAPI_SEND_INTERVAL_S", "10")
    try:
        interval = float(raw_interval)
    except ValueError:
        interval = -1.0
    if not 0.05 <= interval <= 3600:
        raise ConfigError(f"TELELAB_XAPI_SEND_INTERVAL_S must be a number of seconds from 0.05 to 3600, "
                          f"not {raw_interval!r}.")
    if lrs and not homepage:
        raise ConfigError("TELELAB_XAPI_HOMEPAGE must be the lab's address (https://telelab.example.edu) when "
                          "TELELAB_XAPI_LRS_URL is set: every statement's activities and accounts start with it.")
    return XapiSettings(
        lrs_url=_http_url(lrs, "TELELAB_XAPI_LRS_URL") if lrs else None,
        username=_setting(app, "XAPI_LRS_USERNAME", "TELELAB_XAPI_LRS_USERNAME"),
        password=_setting(app, "XAPI_LRS_PASSWORD", "TELELAB_XAPI_LRS_PASSWORD"),
        homepage=_http_url(homepage, "TELELAB_XAPI_HOMEPAGE") if homepage else None,
        interval_s=interval,
    )
