"""programming exercises, code versions and graded runs (issue 32)

Revision ID: 0027
Revises: 0026
Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0027"
down_revision = "0026"
branch_labels = None
depends_on = None


def _when(name: str, nullable: bool = False) -> sa.Column:
    return sa.Column(name, sa.DateTime(timezone=True), nullable=nullable)


def upgrade() -> None:
    op.create_table(
        "exercises",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("slug", sa.String(length=64), nullable=False),
        sa.Column("title", sa.String(length=120), nullable=False),
        sa.Column("statement", sa.Text(), nullable=False),
        sa.Column("template", sa.Text(), nullable=False),
        sa.Column("scene", sa.String(length=64), nullable=False),
        sa.Column("rubric_json", sa.Text(), nullable=False),
        sa.Column("start_json", sa.Text(), nullable=False),
        sa.Column("random_starts_json", sa.Text(), nullable=False),
        sa.Column("time_limit_s", sa.Float(), nullable=False),
        sa.Column("created_by_id", sa.Integer(), nullable=True),
        _when("created_at"),
        _when("updated_at"),
        sa.ForeignKeyConstraint(["created_by_id"], ["users.id"], name=op.f("fk_exercises_created_by_id_users"),
                                ondelete="SET NULL"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_exercises")),
        sa.UniqueConstraint("slug", name=op.f("uq_exercises_slug")),
    )
    op.create_table(
        "exercise_codes",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("exercise_id", sa.Integer(), nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("code", sa.Text(), nullable=False),
        _when("saved_at"),
        sa.ForeignKeyConstraint(["exercise_id"], ["exercises.id"],
                                name=op.f("fk_exercise_codes_exercise_id_exercises"), ondelete="CASCADE"),
        sa.ForeignKeyConstraint(["user_id"], ["users.id"], name=op.f("fk_exercise_codes_user_id_users"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_exercise_codes")),
    )
    op.create_index(op.f("ix_exercise_codes_exercise_id"), "exercise_codes", ["exercise_id"])
    op.create_index(op.f("ix_exercise_codes_user_id"), "exercise_codes", ["user_id"])
    op.create_table(
        "exercise_runs",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("exercise_id", sa.Integer(), nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("code_id", sa.Integer(), nullable=False),
        sa.Column("robot_name", sa.String(length=64), nullable=False),
        sa.Column("mode", sa.String(length=16), nullable=False),
        sa.Column("seed", sa.Integer(), nullable=False),
        sa.Column("start_json", sa.Text(), nullable=False),
        _when("started_at"),
        _when("ended_at", nullable=True),
        sa.Column("status", sa.String(length=16), nullable=False),
        sa.Column("fraction", sa.Float(), nullable=True),
        sa.Column("feedback", sa.Text(), nullable=False),
        sa.Column("measurements_json", sa.Text(), nullable=False),
        sa.Column("trace_json", sa.Text(), nullable=False),
        sa.Column("report_json", sa.Text(), nullable=False),
        sa.ForeignKeyConstraint(["code_id"], ["exercise_codes.id"],
                                name=op.f("fk_exercise_runs_code_id_exercise_codes"), ondelete="CASCADE"),
        sa.ForeignKeyConstraint(["exercise_id"], ["exercises.id"],
                                name=op.f("fk_exercise_runs_exercise_id_exercises"), ondelete="CASCADE"),
        sa.ForeignKeyConstraint(["user_id"], ["users.id"], name=op.f("fk_exercise_runs_user_id_users"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_exercise_runs")),
    )
    op.create_index(op.f("ix_exercise_runs_exercise_id"), "exercise_runs", ["exercise_id"])
    op.create_index(op.f("ix_exercise_runs_user_id"), "exercise_runs", ["user_id"])
    op.create_table(
        "exercise_assignments",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("course_id", sa.Integer(), nullable=False),
        sa.Column("exercise_id", sa.Integer(), nullable=False),
        _when("deadline_at"),
        sa.Column("points", sa.Float(), nullable=False),
        sa.Column("created_by_id", sa.Integer(), nullable=True),
        _when("created_at"),
        sa.ForeignKeyConstraint(["course_id"], ["courses.id"], name=op.f("fk_exercise_assignments_course_id_courses"),
                                ondelete="CASCADE"),
        sa.ForeignKeyConstraint(["exercise_id"], ["exercises.id"],
                                name=op.f("fk_exercise_assignments_exercise_id_exercises"), ondelete="CASCADE"),
        sa.ForeignKeyConstraint(["created_by_id"], ["users.id"],
                                name=op.f("fk_exercise_assignments_created_by_id_users"), ondelete="SET NULL"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_exercise_assignments")),
        sa.UniqueConstraint("course_id", "exercise_id", name="uq_exercise_assignments_course_exercise"),
    )
    op.create_index(op.f("ix_exercise_assignments_course_id"), "exercise_assignments", ["course_id"])


def downgrade() -> None:
    op.drop_table("exercise_assignments")
    op.drop_table("exercise_runs")
    op.drop_table("exercise_codes")
    op.drop_table("exercises")
