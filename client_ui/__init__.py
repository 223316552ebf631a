"""The browser tier: Jinja page shells and ES modules. No business rules live here (see README.md)."""

from __future__ import annotations

from pathlib import Path

TEMPLATE_FOLDER = Path(__file__).resolve().parent / "templates"
STATIC_FOLDER = Path(__file__).resolve().parent / "static"
