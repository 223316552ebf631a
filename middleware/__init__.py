"""Telelab's middleware: the Flask application that decides who may do what, and bridges to the robots.

`create_app` lives in `app.py` and is imported from here on first use (`from middleware import create_app`, gunicorn's
`middleware:create_app()`): a process that needs one module of the package (a recordings writer child, a Ray actor)
does not import every area of the application with it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from middleware.app import create_app

__all__ = ["create_app"]


def __getattr__(name: str) -> Any:
    if name == "create_app":
        from middleware.app import create_app

        return create_app
    raise AttributeError(f"module 'middleware' has no attribute {name!r}")
