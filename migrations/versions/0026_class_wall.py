"""the class wall: raised hands, tutor takeovers, class chat (issue 31)

Revision ID: 0026
Revises: 0025
Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0026"
down_revision = "0025"
branch_labels = None
depends_on = None


def _session_and_user(table: str, user_column: str = "user_id", nullable: bool = False) -> list[sa.SchemaItem]:
    return [
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("session_id", sa.Integer(), nullable=False),
        sa.Column(user_column, sa.Integer(), nullable=nullable),
        sa.ForeignKeyConstraint(["session_id"], ["class_sessions.id"],
                                name=op.f(f"fk_{table}_session_id_class_sessions"), ondelete="CASCADE"),
        sa.ForeignKeyConstraint([user_column], ["users.id"], name=op.f(f"fk_{table}_{user_column}_users"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f(f"pk_{table}")),
    ]


def upgrade() -> None:
    op.create_table(
        "class_hands", *_session_and_user("class_hands"),
        sa.Column("text", sa.String(length=300), nullable=False),
        sa.Column("raised_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("answered_at", sa.DateTime(timezone=True), nullable=True),
        sa.Column("answered_by_id", sa.Integer(), nullable=True),
        sa.ForeignKeyConstraint(["answered_by_id"], ["users.id"], name=op.f("fk_class_hands_answered_by_id_users"),
                                ondelete="SET NULL"),
    )
    op.create_index(op.f("ix_class_hands_session_id"), "class_hands", ["session_id"])
    op.create_index("uq_class_hands_open", "class_hands", ["session_id", "user_id"], unique=True,
                    sqlite_where=sa.text("answered_at IS NULL"), postgresql_where=sa.text("answered_at IS NULL"))
    op.create_table(
        "class_takeovers", *_session_and_user("class_takeovers"),
        sa.Column("tutor_id", sa.Integer(), nullable=False),
        sa.Column("robot_name", sa.String(length=32), nullable=False),
        sa.Column("started_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("heard_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("ended_at", sa.DateTime(timezone=True), nullable=True),
        sa.ForeignKeyConstraint(["tutor_id"], ["users.id"], name=op.f("fk_class_takeovers_tutor_id_users"),
                                ondelete="CASCADE"),
    )
    op.create_index(op.f("ix_class_takeovers_session_id"), "class_takeovers", ["session_id"])
    op.create_index("uq_class_takeovers_open_robot", "class_takeovers", ["robot_name"], unique=True,
                    sqlite_where=sa.text("ended_at IS NULL"), postgresql_where=sa.text("ended_at IS NULL"))
    op.create_table(
        "class_notices", *_session_and_user("class_notices", nullable=True),
        sa.Column("from_id", sa.Integer(), nullable=True),
        sa.Column("kind", sa.String(length=16), nullable=False),
        sa.Column("body", sa.JSON(), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.CheckConstraint("kind IN ('note', 'pointer', 'push')", name=op.f("ck_class_notices_kind_known")),
        sa.ForeignKeyConstraint(["from_id"], ["users.id"], name=op.f("fk_class_notices_from_id_users"),
                                ondelete="SET NULL"),
    )
    op.create_index(op.f("ix_class_notices_session_id"), "class_notices", ["session_id"])


def downgrade() -> None:
    op.drop_table("class_notices")
    op.drop_table("class_takeovers")
    op.drop_table("class_hands")
