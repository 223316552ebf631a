"""Embedded use: which origins may frame Telelab's pages (frame-ancestors), and whether the session cookie must
cross sites (SameSite=None; Secure, over HTTPS only) because a platform is registered."""

from __future__ import annotations

from flask import Flask

from middleware.db import session_factory
from middleware.lti.platforms import FrameOrigins

_KEY = "telelab.lti.frame_origins"


def init_app(app: Flask) -> None:
    """Reads the registered platforms' origins for this app (cached; any worker's change drops the cache)."""
    app.extensions[_KEY] = FrameOrigins(session_factory(app).kw["bind"])


def frame_origins(app: Flask) -> tuple[str, ...]:
    """The origins allowed to frame the pages; empty: none may."""
    origins: FrameOrigins | None = app.extensions.get(_KEY)
    return origins.get() if origins is not None else ()


def frame_ancestors(app: Flask) -> str:
    """The CSP frame-ancestors source list: the registered platforms' origins, else 'none'."""
    return " ".join(frame_origins(app)) or "'none'"


def embedded(app: Flask) -> bool:
    """True when some platform is registered (LTI mode: cookies must reach Telelab inside the LMS's frame)."""
    return bool(frame_origins(app))
