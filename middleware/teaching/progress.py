"""What a learner finished: a lesson watched to its end, a tour followed to its last step (usage analytics and its
xAPI statements read them). Written in the caller's unit of work; a repeat within a minute is the same event (a
page that reports twice)."""

from __future__ import annotations

from datetime import timedelta

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.models.accounts import utc_now
from middleware.models.analytics import LEARNING_EVENT_KINDS, LearningEvent

REPEAT_WITHIN_S = 60.0


def note_finished(session: Session, user_id: int, kind: str, object_id: int) -> bool:
    """Records that user_id finished the lesson or tour object_id (kind: lesson_watched | tour_followed); False when
    the same was recorded within the last minute."""
    if kind not in LEARNING_EVENT_KINDS:
        raise ValueError(f"unknown learning event {kind!r}")
    now = utc_now()
    recent = session.scalar(select(LearningEvent.id).where(
        LearningEvent.user_id == user_id, LearningEvent.kind == kind, LearningEvent.object_id == object_id,
        LearningEvent.at > now - timedelta(seconds=REPEAT_WITHIN_S)).limit(1))
    if recent is not None:
        return False
    session.add(LearningEvent(user_id=user_id, kind=kind, object_id=object_id, at=now))
    session.flush()
    return True
