"""Telelab's middleware: the Flask application that decides who may do what, and bridges to the robots."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from flask import Flask, redirect, url_for
from flask_login import LoginManager, current_user
from flask_wtf.csrf import CSRFProtect

from middleware import config as config_module
from middleware import db
from middleware.auth import identity, sessions
from middleware.errors import register_error_handlers
from middleware.models import User
from middleware.robots import registry

CLIENT_UI_DIR = Path(__file__).resolve().parent.parent / "client_ui"

csrf = CSRFProtect()
login_manager = LoginManager()
login_manager.login_view = "auth.login"
login_manager.login_message = "Log in to open the lab."
login_manager.session_protection = "strong"


@login_manager.user_loader
def _load_user(user_id: str) -> User | None:
    if not user_id.isdigit():
        return None
    user = identity.load_user(db.get_session(), int(user_id))
    return user if user is not None and sessions.opened_with_current_password(user) else None


@login_manager.unauthorized_handler
def _unauthorized():  # type: ignore[no-untyped-def]
    from flask import request

    from middleware.errors import ApiError

    if request.path.startswith("/api/"):
        raise ApiError(401, "not_logged_in", "Log in first; your session may have ended.")
    return redirect(url_for("auth.login", next=request.full_path.rstrip("?")))


def create_app(config: dict[str, Any] | None = None) -> Flask:
    """The Telelab web application; config overrides the TELELAB_* environment."""
    app = Flask(
        __name__,
        template_folder=str(CLIENT_UI_DIR / "templates"),
        static_folder=str(CLIENT_UI_DIR / "static"),
        instance_relative_config=True,
    )
    app.config.from_mapping(config_module.from_environment(Path(app.instance_path)))
    if config:
        app.config.update(config)

    db.init_app(app)
    csrf.init_app(app)
    login_manager.init_app(app)
    registry.init_app(app)
    register_error_handlers(app)

    from middleware.access import sockets as access_sockets
    from middleware.accounts.routes import blueprint as accounts_blueprint
    from middleware.assessment.pages import blueprint as assessment_pages_blueprint
    from middleware.assessment.routes import blueprint as assessment_blueprint
    from middleware.auth.routes import blueprint as auth_blueprint
    from middleware.bookings.routes import blueprint as bookings_blueprint
    from middleware.chat.routes import blueprint as chat_blueprint
    from middleware.courses.routes import blueprint as courses_blueprint
    from middleware.experiment.routes import blueprint as experiment_blueprint
    from middleware.lab import skill_sockets, sockets  # noqa: F401 - importing registers the channels
    from middleware.lab.routes import blueprint as lab_blueprint
    from middleware.lab.skills import blueprint as skills_blueprint
    from middleware.preferences.routes import blueprint as preferences_blueprint

    app.register_blueprint(auth_blueprint)
    app.register_blueprint(lab_blueprint)
    app.register_blueprint(skills_blueprint)
    app.register_blueprint(preferences_blueprint)
    app.register_blueprint(bookings_blueprint)
    app.register_blueprint(chat_blueprint)
    app.register_blueprint(accounts_blueprint)
    app.register_blueprint(courses_blueprint)
    app.register_blueprint(experiment_blueprint)
    app.register_blueprint(assessment_blueprint)
    app.register_blueprint(assessment_pages_blueprint)
    sockets.init_app(app)
    access_sockets.init_app(app)

    from middleware.lessons.routes import blueprint as lessons_blueprint
    from middleware.practice import manager as practice_manager
    from middleware.practice.routes import blueprint as practice_blueprint
    from middleware.tours.routes import blueprint as tours_blueprint

    practice_manager.init_app(app)
    app.register_blueprint(practice_blueprint)
    app.register_blueprint(lessons_blueprint)
    app.register_blueprint(tours_blueprint)

    @app.get("/")
    def home():  # type: ignore[no-untyped-def]
        return redirect(url_for("lab.index" if current_user.is_authenticated else "auth.login"))

    @app.get("/healthz")
    def health():  # type: ignore[no-untyped-def]
        return {"status": "ok"}

    @app.after_request
    def _security_headers(response):  # type: ignore[no-untyped-def]
        response.headers.setdefault("X-Content-Type-Options", "nosniff")
        response.headers.setdefault("X-Frame-Options", "DENY")
        response.headers.setdefault("Referrer-Policy", "same-origin")
        response.headers.setdefault(
            "Content-Security-Policy",
            "default-src 'self'; img-src 'self' blob: data:; connect-src 'self' ws: wss:; "
            "style-src 'self'; script-src 'self'; object-src 'none'; frame-ancestors 'none'",
        )
        return response

    return app
