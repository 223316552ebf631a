"""a course's test of an exercise has a leaderboard its tutors open to the course's students (closed by default)

Revision ID: 0031
Revises: 0030
Create Date: 2026-11-29
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0031"
down_revision = "0030"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("exercise_assignments", schema=None) as batch_op:
        batch_op.add_column(sa.Column("leaderboard_open", sa.Boolean(), nullable=False, server_default=sa.false()))


def downgrade() -> None:
    with op.batch_alter_table("exercise_assignments", schema=None) as batch_op:
        batch_op.drop_column("leaderboard_open")
