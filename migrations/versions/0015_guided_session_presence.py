"""who is present in a live class, shared by every web worker (one row per open page); which process records an
experimental attempt, so another takes it over when that process dies

Revision ID: 0015
Revises: 0014
Create Date: 2026-11-26
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0015"
down_revision = "0014"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "guided_session_presence",
        sa.Column("id", sa.Integer(), primary_key=True),
        sa.Column("session_id", sa.Integer(), sa.ForeignKey("guided_sessions.id", ondelete="CASCADE"), nullable=False),
        sa.Column("user_id", sa.Integer(), sa.ForeignKey("users.id", ondelete="CASCADE"), nullable=False),
        sa.Column("socket_key", sa.String(length=96), nullable=False),
        sa.Column("heard_at", sa.DateTime(timezone=True), nullable=False),
        sa.UniqueConstraint("socket_key", name=op.f("uq_guided_session_presence_socket_key")),
    )
    op.create_index(op.f("ix_guided_session_presence_session_id"), "guided_session_presence", ["session_id"])
    with op.batch_alter_table("assessment_attempts") as batch:
        batch.add_column(sa.Column("recorder_key", sa.String(length=96), nullable=True))
        batch.add_column(sa.Column("recorder_heard_at", sa.DateTime(timezone=True), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("assessment_attempts") as batch:
        batch.drop_column("recorder_heard_at")
        batch.drop_column("recorder_key")
    op.drop_index(op.f("ix_guided_session_presence_session_id"), table_name="guided_session_presence")
    op.drop_table("guided_session_presence")
