"""an exercise attached to a course as a test has LMS line items of its own, and its marks go through the grade
outbox (a passback row of an exercise names no test attempt)

Revision ID: 0030
Revises: 0029
Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0030"
down_revision = "0029"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("lti_line_items", schema=None) as batch_op:
        batch_op.add_column(sa.Column("exercise_assignment_id", sa.Integer(), nullable=True))
        batch_op.alter_column("exam_id", existing_type=sa.Integer(), nullable=True)
        batch_op.create_index(batch_op.f("ix_lti_line_items_exercise_assignment_id"), ["exercise_assignment_id"],
                              unique=False)
        batch_op.create_foreign_key(batch_op.f("fk_lti_line_items_exercise_assignment_id_exercise_assignments"),
                                    "exercise_assignments", ["exercise_assignment_id"], ["id"], ondelete="CASCADE")
        batch_op.create_unique_constraint("uq_lti_line_items_context_exercise",
                                          ["context_id", "exercise_assignment_id"])
        batch_op.create_check_constraint(batch_op.f("ck_lti_line_items_one_graded_item"),
                                         "(exam_id IS NULL) <> (exercise_assignment_id IS NULL)")
    with op.batch_alter_table("lti_grade_passbacks", schema=None) as batch_op:
        batch_op.alter_column("attempt_id", existing_type=sa.Integer(), nullable=True)


def downgrade() -> None:
    op.execute("DELETE FROM lti_grade_passbacks WHERE attempt_id IS NULL")  # an exercise's grades and line items
    op.execute("DELETE FROM lti_line_items WHERE exam_id IS NULL")
    with op.batch_alter_table("lti_grade_passbacks", schema=None) as batch_op:
        batch_op.alter_column("attempt_id", existing_type=sa.Integer(), nullable=False)
    with op.batch_alter_table("lti_line_items", schema=None) as batch_op:
        batch_op.drop_constraint(batch_op.f("ck_lti_line_items_one_graded_item"), type_="check")
        batch_op.drop_constraint("uq_lti_line_items_context_exercise", type_="unique")
        batch_op.drop_constraint(batch_op.f("fk_lti_line_items_exercise_assignment_id_exercise_assignments"),
                                 type_="foreignkey")
        batch_op.drop_index(batch_op.f("ix_lti_line_items_exercise_assignment_id"))
        batch_op.alter_column("exam_id", existing_type=sa.Integer(), nullable=False)
        batch_op.drop_column("exercise_assignment_id")
