"""teaching: tours, guided sessions, video lessons

Revision ID: 0007
Revises: 0006
Create Date: 2026-11-22
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0007"
down_revision = "0006"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "tours",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("slug", sa.String(length=64), nullable=False),
        sa.Column("title", sa.String(length=120), nullable=False),
        sa.Column("summary", sa.String(length=500), nullable=False),
        sa.Column("steps_json", sa.Text(), nullable=False),
        sa.Column("author_id", sa.Integer(), nullable=True),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(["author_id"], ["users.id"], name=op.f("fk_tours_author_id_users"),
                                ondelete="SET NULL"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_tours")),
        sa.UniqueConstraint("slug", name=op.f("uq_tours_slug")),
    )
    op.create_table(
        "guided_sessions",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("tour_id", sa.Integer(), nullable=False),
        sa.Column("robot_name", sa.String(length=64), nullable=False),
        sa.Column("tutor_id", sa.Integer(), nullable=False),
        sa.Column("course_id", sa.Integer(), nullable=True),
        sa.Column("step_index", sa.Integer(), nullable=False),
        sa.Column("control_user_id", sa.Integer(), nullable=True),
        sa.Column("version", sa.Integer(), nullable=False),
        sa.Column("started_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("ended_at", sa.DateTime(timezone=True), nullable=True),
        sa.ForeignKeyConstraint(["control_user_id"], ["users.id"],
                                name=op.f("fk_guided_sessions_control_user_id_users"), ondelete="SET NULL"),
        sa.ForeignKeyConstraint(["course_id"], ["courses.id"], name=op.f("fk_guided_sessions_course_id_courses"),
                                ondelete="SET NULL"),
        sa.ForeignKeyConstraint(["tour_id"], ["tours.id"], name=op.f("fk_guided_sessions_tour_id_tours"),
                                ondelete="CASCADE"),
        sa.ForeignKeyConstraint(["tutor_id"], ["users.id"], name=op.f("fk_guided_sessions_tutor_id_users"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_guided_sessions")),
    )
    op.create_index(op.f("ix_guided_sessions_robot_name"), "guided_sessions", ["robot_name"])
    op.create_index(op.f("ix_guided_sessions_tour_id"), "guided_sessions", ["tour_id"])
    op.create_table(
        "lessons",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("slug", sa.String(length=64), nullable=False),
        sa.Column("title", sa.String(length=120), nullable=False),
        sa.Column("summary", sa.String(length=500), nullable=False),
        sa.Column("video_name", sa.String(length=128), nullable=False),
        sa.Column("cues_vtt", sa.Text(), nullable=False),
        sa.Column("author_id", sa.Integer(), nullable=True),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(["author_id"], ["users.id"], name=op.f("fk_lessons_author_id_users"),
                                ondelete="SET NULL"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_lessons")),
        sa.UniqueConstraint("slug", name=op.f("uq_lessons_slug")),
    )


def downgrade() -> None:
    op.drop_table("lessons")
    op.drop_index(op.f("ix_guided_sessions_tour_id"), table_name="guided_sessions")
    op.drop_index(op.f("ix_guided_sessions_robot_name"), table_name="guided_sessions")
    op.drop_table("guided_sessions")
    op.drop_table("tours")
