"""the papers' remaining parts: the thesis' protocol whole (a course's experiment protocol, each participant's
details, learning period and counterbalanced order, trials that delayed commands) and each robot's maintenance log

Revision ID: 0028
Revises: 0027
Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0028"
down_revision = "0027"
branch_labels = None
depends_on = None

_EXPERIENCE = "IN ('none', 'some', 'much')"


def upgrade() -> None:
    op.create_table(
        "experiment_protocols",
        sa.Column("course_id", sa.Integer(), sa.ForeignKey("courses.id", ondelete="CASCADE",
                                                          name=op.f("fk_experiment_protocols_course_id_courses")),
                  primary_key=True),
        sa.Column("learning_s", sa.Integer(), nullable=False),
        sa.Column("delay_commands", sa.Boolean(), nullable=False),
        sa.Column("export_participants", sa.Boolean(), nullable=False),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.CheckConstraint("learning_s >= 0 AND learning_s <= 3600",
                           name=op.f("ck_experiment_protocols_learning_in_range")),
    )
    op.create_table(
        "experiment_participants",
        sa.Column("user_id", sa.Integer(), sa.ForeignKey("users.id", ondelete="CASCADE",
                                                        name=op.f("fk_experiment_participants_user_id_users")),
                  primary_key=True),
        sa.Column("consent", sa.Boolean(), nullable=False),
        sa.Column("age", sa.Integer(), nullable=True),
        sa.Column("location", sa.String(8), nullable=True),
        sa.Column("games_experience", sa.String(8), nullable=True),
        sa.Column("robots_experience", sa.String(8), nullable=True),
        sa.Column("answered_at", sa.DateTime(timezone=True), nullable=True),
        sa.Column("learning_started_at", sa.DateTime(timezone=True), nullable=True),
        sa.Column("order_course_id", sa.Integer(),
                  sa.ForeignKey("courses.id", ondelete="SET NULL",
                                name=op.f("fk_experiment_participants_order_course_id_courses")), nullable=True),
        sa.Column("order_index", sa.Integer(), nullable=True),
        sa.CheckConstraint("age IS NULL OR (age >= 10 AND age <= 120)",
                           name=op.f("ck_experiment_participants_age_in_range")),
        sa.CheckConstraint("location IS NULL OR location IN ('lab', 'remote')",
                           name=op.f("ck_experiment_participants_location_known")),
        sa.CheckConstraint(f"games_experience IS NULL OR games_experience {_EXPERIENCE}",
                           name=op.f("ck_experiment_participants_games_experience_known")),
        sa.CheckConstraint(f"robots_experience IS NULL OR robots_experience {_EXPERIENCE}",
                           name=op.f("ck_experiment_participants_robots_experience_known")),
    )
    with op.batch_alter_table("experiment_trials") as batch:
        batch.add_column(sa.Column("commands_delayed", sa.Boolean(), nullable=False, server_default=sa.false()))
    op.create_table(
        "robot_maintenance",
        sa.Column("id", sa.Integer(), primary_key=True),
        sa.Column("robot_name", sa.String(64), nullable=False),
        sa.Column("actor_id", sa.Integer(), sa.ForeignKey("users.id", ondelete="SET NULL",
                                                         name=op.f("fk_robot_maintenance_actor_id_users")),
                  nullable=True),
        sa.Column("action", sa.String(16), nullable=False),
        sa.Column("outcome", sa.String(500), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
    )
    op.create_index(op.f("ix_robot_maintenance_robot_name"), "robot_maintenance", ["robot_name"])


def downgrade() -> None:
    op.drop_index(op.f("ix_robot_maintenance_robot_name"), table_name="robot_maintenance")
    op.drop_table("robot_maintenance")
    with op.batch_alter_table("experiment_trials") as batch:
        batch.drop_column("commands_delayed")
    op.drop_table("experiment_participants")
    op.drop_table("experiment_protocols")
