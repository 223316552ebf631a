"""Account pages and API: one module per thing administered, all on the one "accounts" blueprint (its
endpoint names are what templates' url_for use). create_app registers `blueprint`; listing the modules
here is what declares their views on it."""

from __future__ import annotations

from middleware.accounts import invitation_routes, robot_routes, throttle_routes, user_routes
from middleware.accounts.web import blueprint

VIEW_MODULES = (user_routes, invitation_routes, robot_routes, throttle_routes)

__all__ = ["VIEW_MODULES", "blueprint"]
