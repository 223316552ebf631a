"""A robot's refusal or absence is a Refused: a view lets it pass and the one handler renders it (issue 28)."""

from __future__ import annotations

import pytest
from flask import Flask

from middleware.errors import Refused, register_error_handlers
from middleware.robots.refusals import NOT_CONTROLLER_MESSAGE, CommandRefused, RobotUnavailable


def app_raising(error: Exception) -> Flask:
    """A bare app with the middleware's error handlers and one API view that raises error."""
    app = Flask(__name__)
    register_error_handlers(app)

    @app.get("/api/robot")
    def robot() -> str:
        raise error

    return app


@pytest.mark.parametrize(("error", "status", "body"), [
    (RobotUnavailable("The robot did not answer in time."), 503,
     {"code": "robot_offline", "message": "The robot did not answer in time. Try again in a moment.", "field": None}),
    (CommandRefused("invalid_field", "speed_mps must be at most 0.5.", "speed_mps"), 400,
     {"code": "invalid_field", "message": "speed_mps must be at most 0.5.", "field": "speed_mps"}),
    (CommandRefused("not_found", "no skill wander", "skill"), 404,
     {"code": "unknown_skill", "message": "no skill wander", "field": "skill"}),
    (CommandRefused("not_found", "no goal g-1", None, not_found_code="unknown_goal"), 404,
     {"code": "unknown_goal", "message": "no goal g-1", "field": None}),
    (CommandRefused("not_possible_now", "the base is taken", None), 409,
     {"code": "busy", "message": "the base is taken", "field": None}),
    (CommandRefused("unauthenticated", "stale token", "token"), 403,
     {"code": "not_controller", "message": NOT_CONTROLLER_MESSAGE, "field": None}),
])
def test_a_robot_error_a_view_lets_pass_is_rendered_by_the_one_handler(error: Exception, status: int,
                                                                        body: dict[str, object]) -> None:
    answer = app_raising(error).test_client().get("/api/robot")
    assert (answer.status_code, answer.get_json()) == (status, {"error": body})


def test_a_robot_error_keeps_the_robots_own_words_and_reason() -> None:
    refused = CommandRefused("not_possible_now", "the base is taken")
    assert isinstance(refused, Refused) and isinstance(RobotUnavailable("x"), Refused)
    assert (refused.reason, refused.detail, str(refused)) == ("not_possible_now", "the base is taken",
                                                              "the base is taken")
    assert str(RobotUnavailable("The link to lab-1 is closed.")) == "The link to lab-1 is closed."
