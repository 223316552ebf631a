"""class priority override: the admin who let a live class outrank the queue without a booking

Revision ID: 0011
Revises: 0010
Create Date: 2026-11-23
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0011"
down_revision = "0010"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("guided_sessions", schema=None) as batch_op:
        batch_op.add_column(sa.Column("priority_override_by_id", sa.Integer(), nullable=True))
        batch_op.create_foreign_key(batch_op.f("fk_guided_sessions_priority_override_by_id_users"), "users",
                                    ["priority_override_by_id"], ["id"], ondelete="SET NULL")


def downgrade() -> None:
    with op.batch_alter_table("guided_sessions", schema=None) as batch_op:
        batch_op.drop_constraint(batch_op.f("fk_guided_sessions_priority_override_by_id_users"), type_="foreignkey")
        batch_op.drop_column("priority_override_by_id")
