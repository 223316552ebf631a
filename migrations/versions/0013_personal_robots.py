"""personal robots and class sessions: the robots the farm runs for users, recorded so every web worker finds them;
and each course's longest hold of a shared robot by a graded run

Revision ID: 0013
Revises: 0012
Create Date: 2026-11-25
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0013"
down_revision = "0012"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("courses") as batch:
        batch.add_column(sa.Column("graded_run_hold_min", sa.Integer(), nullable=False, server_default="30"))
        batch.create_check_constraint("graded_run_hold_range", "graded_run_hold_min BETWEEN 5 AND 240")
    op.create_table(
        "class_sessions",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("course_id", sa.Integer(), nullable=False),
        sa.Column("started_by_id", sa.Integer(), nullable=True),
        sa.Column("started_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("ended_at", sa.DateTime(timezone=True), nullable=True),
        sa.ForeignKeyConstraint(["course_id"], ["courses.id"], name=op.f("fk_class_sessions_course_id_courses"),
                                ondelete="CASCADE"),
        sa.ForeignKeyConstraint(["started_by_id"], ["users.id"], name=op.f("fk_class_sessions_started_by_id_users"),
                                ondelete="SET NULL"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_class_sessions")),
    )
    op.create_index("uq_class_sessions_open_course", "class_sessions", ["course_id"], unique=True,
                    sqlite_where=sa.text("ended_at IS NULL"), postgresql_where=sa.text("ended_at IS NULL"))
    op.create_table(
        "class_seats",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("session_id", sa.Integer(), nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("state", sa.String(length=16), nullable=False),
        sa.Column("message", sa.String(length=300), nullable=False),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.CheckConstraint("state IN ('starting', 'ready', 'failed', 'stopped')",
                           name=op.f("ck_class_seats_state_known")),
        sa.ForeignKeyConstraint(["session_id"], ["class_sessions.id"],
                                name=op.f("fk_class_seats_session_id_class_sessions"), ondelete="CASCADE"),
        sa.ForeignKeyConstraint(["user_id"], ["users.id"], name=op.f("fk_class_seats_user_id_users"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_class_seats")),
        sa.UniqueConstraint("session_id", "user_id", name="uq_class_seats_session_user"),
    )
    op.create_index(op.f("ix_class_seats_session_id"), "class_seats", ["session_id"])
    op.create_table(
        "personal_robots",
        sa.Column("name", sa.String(length=32), nullable=False),
        sa.Column("owner_id", sa.Integer(), nullable=False),
        sa.Column("owner_name", sa.String(length=64), nullable=False),
        sa.Column("scene", sa.String(length=64), nullable=False),
        sa.Column("token", sa.String(length=64), nullable=False),
        sa.Column("address", sa.String(length=255), nullable=False),
        sa.Column("backend", sa.String(length=16), nullable=False),
        sa.Column("started_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("last_used_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("class_session_id", sa.Integer(), nullable=True),
        sa.ForeignKeyConstraint(["class_session_id"], ["class_sessions.id"],
                                name=op.f("fk_personal_robots_class_session_id_class_sessions"), ondelete="SET NULL"),
        sa.ForeignKeyConstraint(["owner_id"], ["users.id"], name=op.f("fk_personal_robots_owner_id_users"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("name", name=op.f("pk_personal_robots")),
        sa.UniqueConstraint("owner_id", name=op.f("uq_personal_robots_owner_id")),
    )


def downgrade() -> None:
    op.drop_table("personal_robots")
    op.drop_table("class_seats")
    op.drop_table("class_sessions")
    with op.batch_alter_table("courses") as batch:
        batch.drop_constraint("ck_courses_graded_run_hold_range", type_="check")
        batch.drop_column("graded_run_hold_min")
