"""The Flask application: create_app composes every area, its hooks and its blueprints."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path
from typing import Any

from flask import Flask, Response, redirect, url_for
from flask.typing import ResponseReturnValue
from flask_login import current_user
from sqlalchemy.orm import Session

from middleware import analytics, browser_modules, db, i18n, realtime, validation
from middleware import config as config_module
from middleware.access import commands
from middleware.access import coordinator as access_coordinator
from middleware.access import sockets as access_sockets
from middleware.access.coordinator import AccessHooks
from middleware.access.graded_runs import robots_in_graded_runs, with_graded_run_priority
from middleware.accounts import routes as accounts_routes
from middleware.analytics import routes as analytics_routes
from middleware.api import routes as api_routes
from middleware.assessment import attempts
from middleware.assessment import pages as assessment_pages
from middleware.assessment import routes as assessment_routes
from middleware.auth import cookies as auth_cookies
from middleware.auth import routes as auth_routes
from middleware.auth import services as auth_services
from middleware.bookings import routes as bookings_routes
from middleware.bookings import services as bookings_services
from middleware.chat import routes as chat_routes
from middleware.chat import sockets as chat_sockets
from middleware.courses import routes as courses_routes
from middleware.errors import register_error_handlers
from middleware.exercises import routes as exercises_routes
from middleware.exercises import services as exercises_services
from middleware.experiment import delay, trial_rules
from middleware.experiment import routes as experiment_routes
from middleware.extensions import csrf, login_manager, socket_login_check
from middleware.farm import setup as farm_setup
from middleware.lab import limits_routes, pool_routes, robot_health_routes
from middleware.lab import routes as lab_routes
from middleware.lab import skills as lab_skills
from middleware.lab import sockets as lab_sockets
from middleware.lab import teleperception_routes as lab_teleperception
from middleware.lti import embedding as lti_embedding
from middleware.lti import grades as lti_grades
from middleware.lti import routes as lti_routes
from middleware.lti import setup as lti_setup
from middleware.plans import routes as plans_routes
from middleware.preferences import language as language_routes
from middleware.preferences import routes as preferences_routes
from middleware.recordings import parts as recordings
from middleware.recordings import routes as recordings_routes
from middleware.robots import registry
from middleware.teaching import (
    class_routes,
    class_wall,
    class_wall_live,
    class_wall_routes,
    farm_routes,
    lesson_routes,
    practice_robots,
    practice_routes,
    tour_live,
    tour_routes,
)
from middleware.teaching.tours import robots_in_live_classes, with_guided_priority
from middleware.wording import moment_words, number_words

CLIENT_UI_DIR = Path(__file__).resolve().parent.parent / "client_ui"

def create_app(config: dict[str, Any] | None = None) -> Flask:
    """The Telelab web application; config overrides the TELELAB_* environment."""
    app = Flask(
        "middleware",
        template_folder=str(CLIENT_UI_DIR / "templates"),
        static_folder=str(CLIENT_UI_DIR / "static"),
        instance_relative_config=True,
    )
    app.config.from_mapping(config_module.from_environment(Path(app.instance_path)))
    if config:
        app.config.update(config)

    validation.init_app(app)
    i18n.init_app(app)
    app.add_template_filter(moment_words, "moment")
    app.add_template_filter(number_words, "number")
    db.init_app(app)
    auth_cookies.init_app(app)
    auth_services.make_timing_equaliser()
    csrf.init_app(app)
    login_manager.init_app(app)
    register_error_handlers(app)
    import_map_source = browser_modules.init_app(app)
    _compose_robot_access(app)
    _register_areas(app)

    @app.get("/")
    def home() -> ResponseReturnValue:
        return redirect(url_for("lab.index" if current_user.is_authenticated else "auth.login"))

    @app.get("/healthz")
    def health() -> ResponseReturnValue:
        return {"status": "ok"}

    @app.after_request
    def _security_headers(response: Response) -> Response:
        response.headers.setdefault("X-Content-Type-Options", "nosniff")
        framers = lti_embedding.frame_ancestors(app)  # registered LMSs' origins, else 'none'
        if framers == "'none'":
            response.headers.setdefault("X-Frame-Options", "DENY")
        response.headers.setdefault("Referrer-Policy", "same-origin")
        response.headers.setdefault(
            "Content-Security-Policy",
            "default-src 'self'; img-src 'self' blob: data:; connect-src 'self' ws: wss:; "
            f"style-src 'self'; script-src 'self' {import_map_source}; object-src 'none'",
        )
        # Who may frame a page is decided here alone, for a page with a policy of its own too (the exercises').
        policy = response.headers["Content-Security-Policy"]
        if "frame-ancestors" not in policy:
            response.headers["Content-Security-Policy"] = f"{policy}; frame-ancestors {framers}"
        return response

    return app


def _compose_robot_access(app: Flask) -> None:
    """The robots, the access rule with the hooks graded runs, bookings and live classes add to it, the practice robots,
    and the one command path over them (the areas themselves never import one another for these)."""
    robots = registry.init_app(app)
    priority = with_graded_run_priority(with_guided_priority(bookings_services.priority_user_id))

    def priority_robots(session: Session, now: datetime) -> set[str]:  # the robots priority may speak of now
        return (bookings_services.robots_with_bookings_now(session, now) | robots_in_live_classes(session)
                | robots_in_graded_runs(session, now))

    coordinator = access_coordinator.init_app(app, AccessHooks(priority, bookings_services.check_in,
                                                               priority_robots))
    practice_robots.init_app(app, robots, farm_setup.init_app(app))
    commands.init_app(app, robots, coordinator, (trial_rules.teleoperation_only(db.session_factory(app)),))
    commands.robot_commands(app).oversee(class_wall.WallOversight(db.session_factory(app)))
    preferences_routes.lock_preference(trial_rules.FEEDBACK_PREFERENCE_KEY, trial_rules.feedback_set_by_trial)


def _register_areas(app: Flask) -> None:
    """Each area's pages, API and WebSocket channels."""
    for blueprint in (auth_routes.blueprint, lab_routes.blueprint, lab_skills.blueprint, preferences_routes.blueprint,
                      bookings_routes.blueprint, chat_routes.blueprint, accounts_routes.blueprint,
                      courses_routes.blueprint, experiment_routes.blueprint, assessment_routes.blueprint,
                      assessment_pages.blueprint, practice_routes.blueprint, lesson_routes.blueprint,
                      tour_routes.blueprint, class_routes.blueprint, farm_routes.blueprint, pool_routes.blueprint,
                      limits_routes.blueprint, plans_routes.blueprint, class_wall_routes.blueprint,
                      robot_health_routes.blueprint):
        app.register_blueprint(blueprint)
    app.register_blueprint(lab_teleperception.blueprint)
    app.register_blueprint(language_routes.blueprint)
    app.register_blueprint(exercises_routes.blueprint)
    app.register_blueprint(lti_routes.blueprint)
    lti_setup.init_app(app)
    attempts.on_final_mark(lti_grades.queue_final_mark)  # a final or overridden mark goes to the LMS gradebook
    exercises_services.on_mark_change(lti_grades.queue_exercise_mark)  # so does a changed mark on an exercise test
    auth_cookies.cross_site_when(app, lti_embedding.embedded)
    app.register_blueprint(recordings_routes.blueprint)
    recordings.init_app(app)
    app.register_blueprint(analytics_routes.blueprint)
    analytics.init_app(app)
    app.register_blueprint(api_routes.blueprint)
    realtime.init_app(app, [lab_sockets.register, access_sockets.register, chat_sockets.register,
                            practice_routes.register, tour_live.register, class_wall_live.register], socket_login_check)
    realtime.hold_viewers_with(app, delay.viewer_hold)
    lab_sockets.hold_commands_with(app, delay.command_hold)
