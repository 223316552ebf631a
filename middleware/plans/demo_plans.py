"""The demo plans seeded with the demo course (middleware/demo_course.py): two of the demo student's own (one reacts
to an obstacle with an on block, issue 33) and one the demo tutor shares with the course. All use only the
language's own commands (drive, repeat, wait, say, on), so they are checked without a robot's skill schemas: the
lab's robots may not be running yet when it is seeded."""

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
REACTING_PLAN = ("bump-and-turn", """# Drives ahead; whenever something comes within 40 cm it backs off and turns.
on obstacle_detected 0.4 {
  say "Something ahead: backing off and turning"
  drive -0.1 0 for 1s
  drive 0 0.8 for 2s
}
repeat 8 {
  drive 0.25 0 for 2s
}
say "Done"
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
    for name, text in (STUDENT_PLAN, REACTING_PLAN):
        if student is not None and not _has_plan(session, student.id, name):
            create_plan(session, student, name, check_text(text, {}))
            added.append(f"the demo student's plan {name}")
    if tutor is not None and not _has_plan(session, tutor.id, SHARED_PLAN[0]):
        plan = create_plan(session, tutor, SHARED_PLAN[0], check_text(SHARED_PLAN[1], {}))
        share_plan(session, tutor, plan.id, course_id)
        added.append(f"the plan {SHARED_PLAN[0]} shared with the demo course")
    return added


def _has_plan(session: Session, owner_id: int, name: str) -> bool:
    return session.scalar(select(StoredPlan.id).where(StoredPlan.owner_id == owner_id,
                                                      StoredPlan.name == name)) is not None
