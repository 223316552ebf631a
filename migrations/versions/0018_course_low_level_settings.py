"""per course, which low-level settings its students may change (velocity limits, the watchdog timeout)

Revision ID: 0018
Revises: 0017
Create Date: 2026-11-26
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0018"
down_revision = "0017"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("courses", schema=None) as batch_op:
        batch_op.add_column(sa.Column("students_set_velocity", sa.Boolean(), nullable=False, server_default=sa.true()))
        batch_op.add_column(sa.Column("students_set_watchdog", sa.Boolean(), nullable=False,
                                      server_default=sa.false()))


def downgrade() -> None:
    with op.batch_alter_table("courses", schema=None) as batch_op:
        batch_op.drop_column("students_set_watchdog")
        batch_op.drop_column("students_set_velocity")
