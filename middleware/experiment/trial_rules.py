"""What an open delay trial decides for its student, whatever they use: the robot is driven by hand (teleoperation,
the condition measured), and the motion preview is the trial's. The composition root hands these rules to the one
command path (access/commands.py) and to the preferences; they read the database, so every worker applies them."""

from __future__ import annotations

from collections.abc import Callable

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.models.experiment import TRIAL_OPEN, Trial

FEEDBACK_PREFERENCE_KEY = "camera-feedback"


def open_trial_on(session: Session, user_id: int, robot_name: str | None = None) -> Trial | None:
    """user_id's open trial (on robot_name when given), if any."""
    query = select(Trial).where(Trial.user_id == user_id, Trial.status == TRIAL_OPEN)
    if robot_name is not None:
        query = query.where(Trial.robot_name == robot_name)
    return session.scalar(query.order_by(Trial.id.desc()).limit(1))


def teleoperation_only(session_factory: Callable[[], Session]) -> Callable[[str, int], str | None]:
    """The command path's rule: why user_id may only drive robot_name by hand now (their trial on it is open),
    or None. A go-to-goal, a plan or a placement would make the run something other than the teleoperation the
    trial records."""

    def rule(robot_name: str, user_id: int) -> str | None:
        with session_factory() as session:
            trial = open_trial_on(session, user_id, robot_name)
        if trial is None:
            return None
        return (f"Your delay trial on {robot_name} measures driving by hand: go-to-goal, plans and placing the robot "
                "are off until the trial is recorded or given up.")

    return rule


def feedback_set_by_trial(session: Session, user_id: int) -> str | None:
    """Why the motion-preview preference cannot change now (the open trial set it), or None."""
    trial = open_trial_on(session, user_id)
    if trial is None:
        return None
    return (f"Your delay trial sets the motion preview {'on' if trial.feedback else 'off'} until it is recorded or "
            "given up.")
