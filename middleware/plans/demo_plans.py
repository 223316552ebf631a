"""The demo plans seeded with the demo course (middleware/demo_course.py): one of the demo student's own and one
the demo tutor shares with the course. Both use only the language's own commands (drive, repeat, wait, say), so
they are checked without a robot's skill schemas: the lab's robots may not be running yet when it is seeded."""

from __future__ import annotations

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.auth.services import find_user
from middleware.models import StoredPlan
from middleware.plans.services import check_text, create_plan, share_plan

STUDENT_PLAN = ("square", """# Drives a square of 40 cm sides: four times forward, then a quarter turn on the spot.
say "A square, 40 cm a side"
repeat 4 {
  drive 0.2 0 for 2s
  drive 0 0.5 for 3.14s
}
""")
SHARED_PLAN = ("careful-forward", """# Drives ahead while the way is clear, and says so when something is close.
say "Driving ahead carefully"
set max_speed 0.2
repeat 5 {
  if obstacle_within 0.5 {
    say "Something is close: stopping"
    wait 1s
  } else {
    drive 0.15 0 for 1s
  }
}
""")


def seed_demo_plans(session: Session, course_id: int) -> list[str]:
    """Adds the demo plans that do not exist yet, sharing one with the demo course (the caller commits); what was
    added."""
    added: list[str] = []
    student, tutor = find_user(session, "student"), find_user(session, "tutor")
    if student is not None and not _has_plan(session, student.id, STUDENT_PLAN[0]):
        create_plan(session, student, STUDENT_PLAN[0], check_text(STUDENT_PLAN[1], {}))
        added.append(f"the demo student's plan {STUDENT_PLAN[0]}")
    if tutor is not None and not _has_plan(session, tutor.id, SHARED_PLAN[0]):
        plan = create_plan(session, tutor, SHARED_PLAN[0], check_text(SHARED_PLAN[1], {}))
        share_plan(session, tutor, plan.id, course_id)
        added.append(f"the plan {SHARED_PLAN[0]} shared with the demo course")
    return added


def _has_plan(session: Session, owner_id: int, name: str) -> bool:
    return session.scalar(select(StoredPlan.id).where(StoredPlan.owner_id == owner_id,
                                                      StoredPlan.name == name)) is not None
