"""A robot's refusals as people and API clients see them: the one map from the skill server's answer to a `Refused`.

A robot that does not answer is a 503 `robot_offline`; a command it refuses keeps the robot's own reason
(`reason`: not_found, invalid_field, not_controller, unauthenticated, not_possible_now) and is shown with the
status and stable code of this table. Both are `Refused`, so routes let them pass to the one handler.
"""

from __future__ import annotations

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.errors import Refused
from middleware.i18n import N_

STALE_TOKEN_CODES = frozenset({"not_controller", "unauthenticated"})
STATUS_OF_REFUSAL = {"invalid_field": 400, "not_found": 404, "not_controller": 403, "unauthenticated": 403,
                     "not_possible_now": 409}
NOT_CONTROLLER_MESSAGE = N_("You are observing: someone else has control. Wait for your turn.")


class RobotUnavailable(Refused):
    """The skill server did not answer in time, or refused for a reason the caller cannot fix (503 robot_offline).

    str() is the reason alone ("The robot did not answer in time."); the message adds what to do.
    """

    def __init__(self, reason: str) -> None:
        super().__init__(503, "robot_offline", gettext("%(reason)s Try again in a moment.", reason=reason))
        self.reason = reason

    def __str__(self) -> str:
        return self.reason


class CommandRefused(Refused):
    """The skill server refused a command: `reason` is the robot's own code, `detail` its own words, field the
    offending input when it is one; status, code and message are what a person or API client sees.

    not_found_code names what was not found (a skill unless told: `unknown_goal` for a goal's id).
    """

    def __init__(self, reason: str, detail: str, field: str | None = None,
                 not_found_code: str = "unknown_skill") -> None:
        status = STATUS_OF_REFUSAL.get(reason, 400)
        if reason == "not_possible_now":
            super().__init__(status, "busy", detail, field)
        elif reason in STALE_TOKEN_CODES:
            super().__init__(status, "not_controller", gettext(NOT_CONTROLLER_MESSAGE))
        else:
            super().__init__(status, not_found_code if reason == "not_found" else reason, detail, field)
        self.reason, self.detail = reason, detail

    def __str__(self) -> str:
        return self.detail
