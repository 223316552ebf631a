"""the course a delay trial counts for, so only that course's tutors read it

Revision ID: 0019
Revises: 0018
Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0019"
down_revision = "0018"
branch_labels = None
depends_on = None

# A trial run before this revision counts for its student's course when they are a student of exactly one.
BACKFILL = """
UPDATE experiment_trials SET course_id = (
    SELECT m.course_id FROM course_memberships m WHERE m.user_id = experiment_trials.user_id AND m.role = 'student')
WHERE (SELECT count(*) FROM course_memberships m
       WHERE m.user_id = experiment_trials.user_id AND m.role = 'student') = 1
"""


def upgrade() -> None:
    with op.batch_alter_table("experiment_trials", schema=None) as batch_op:
        batch_op.add_column(sa.Column("course_id", sa.Integer(), nullable=True))
        batch_op.create_index(batch_op.f("ix_experiment_trials_course_id"), ["course_id"], unique=False)
        batch_op.create_foreign_key(batch_op.f("fk_experiment_trials_course_id_courses"), "courses", ["course_id"],
                                    ["id"], ondelete="SET NULL")
    op.execute(BACKFILL)


def downgrade() -> None:
    with op.batch_alter_table("experiment_trials", schema=None) as batch_op:
        batch_op.drop_constraint(batch_op.f("fk_experiment_trials_course_id_courses"), type_="foreignkey")
        batch_op.drop_index(batch_op.f("ix_experiment_trials_course_id"))
        batch_op.drop_column("course_id")
