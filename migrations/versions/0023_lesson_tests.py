"""a lesson may name a test before (its cues wait for it) and a test after, compared per part

Revision ID: 0023
Revises: 0022
Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0023"
down_revision = "0022"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("lessons") as batch:
        for column in ("before_exam_id", "after_exam_id"):
            batch.add_column(sa.Column(column, sa.Integer(), nullable=True))
            batch.create_foreign_key(op.f(f"fk_lessons_{column}_assessment_exams"), "assessment_exams", [column],
                                     ["id"], ondelete="SET NULL")


def downgrade() -> None:
    with op.batch_alter_table("lessons") as batch:
        for column in ("before_exam_id", "after_exam_id"):
            batch.drop_constraint(op.f(f"fk_lessons_{column}_assessment_exams"), type_="foreignkey")
            batch.drop_column(column)
