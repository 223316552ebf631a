"""delay and trials: per-user injected video delay, and teleoperation-under-delay trials

Revision ID: 0006
Revises: 0005
Create Date: 2026-11-21
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0006"
down_revision = "0005"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "video_delays",
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("delay_s", sa.Float(), nullable=False),
        sa.Column("set_by_id", sa.Integer(), nullable=True),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.CheckConstraint("delay_s >= 0 AND delay_s <= 7", name=op.f("ck_video_delays_delay_in_range")),
        sa.ForeignKeyConstraint(["set_by_id"], ["users.id"], name=op.f("fk_video_delays_set_by_id_users"),
                                ondelete="SET NULL"),
        sa.ForeignKeyConstraint(["user_id"], ["users.id"], name=op.f("fk_video_delays_user_id_users"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("user_id", name=op.f("pk_video_delays")),
    )
    op.create_table(
        "experiment_trials",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("robot_name", sa.String(length=64), nullable=False),
        sa.Column("course", sa.String(length=16), nullable=False),
        sa.Column("delay_s", sa.Float(), nullable=False),
        sa.Column("feedback", sa.Boolean(), nullable=False),
        sa.Column("status", sa.String(length=16), nullable=False),
        sa.Column("total_time_s", sa.Float(), nullable=True),
        sa.Column("errors", sa.Integer(), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("finished_at", sa.DateTime(timezone=True), nullable=True),
        sa.CheckConstraint("course IN ('course-A', 'course-B')", name=op.f("ck_experiment_trials_course_known")),
        sa.CheckConstraint("status IN ('assigned', 'completed', 'abandoned')",
                           name=op.f("ck_experiment_trials_status_known")),
        sa.CheckConstraint("delay_s >= 0 AND delay_s <= 7", name=op.f("ck_experiment_trials_trial_delay_in_range")),
        sa.ForeignKeyConstraint(["user_id"], ["users.id"], name=op.f("fk_experiment_trials_user_id_users"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_experiment_trials")),
    )
    op.create_index(op.f("ix_experiment_trials_user_id"), "experiment_trials", ["user_id"], unique=False)


def downgrade() -> None:
    op.drop_index(op.f("ix_experiment_trials_user_id"), table_name="experiment_trials")
    op.drop_table("experiment_trials")
    op.drop_table("video_delays")
