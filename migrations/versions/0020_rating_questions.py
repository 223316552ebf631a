"""a bank question may be a 1-5 rating with labelled ends (the 2022 paper's per-part rating)

Revision ID: 0020
Revises: 0019
Create Date: 2026-11-28
"""

from __future__ import annotations

from alembic import op

revision = "0020"
down_revision = "0019"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("assessment_questions") as batch:
        batch.drop_constraint(op.f("ck_assessment_questions_kind_known"), type_="check")
        batch.create_check_constraint("kind_known", "kind IN ('single', 'multiple', 'numeric', 'text', 'rating')")


def downgrade() -> None:
    op.execute("DELETE FROM assessment_questions WHERE kind = 'rating'")
    with op.batch_alter_table("assessment_questions") as batch:
        batch.drop_constraint(op.f("ck_assessment_questions_kind_known"), type_="check")
        batch.create_check_constraint("kind_known", "kind IN ('single', 'multiple', 'numeric', 'text')")
