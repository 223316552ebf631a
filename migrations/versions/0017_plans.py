"""plans (issue 16): a user's named plans, each save a new version holding the text, canonical JSON and summary

Revision ID: 0017
Revises: 0016
Create Date: 2026-11-26
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0017"
down_revision = "0016"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "plans",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("owner_id", sa.Integer(), sa.ForeignKey("users.id", name=op.f("fk_plans_owner_id_users"),
                                                            ondelete="CASCADE"), nullable=False),
        sa.Column("name", sa.String(length=64), nullable=False),
        sa.Column("shared_course_id", sa.Integer(),
                  sa.ForeignKey("courses.id", name=op.f("fk_plans_shared_course_id_courses"), ondelete="SET NULL"),
                  nullable=True),
        sa.Column("latest_version", sa.Integer(), nullable=False),
        sa.Column("console_skill", sa.Boolean(), server_default=sa.false(), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_plans")),
        sa.UniqueConstraint("owner_id", "name", name="uq_plans_owner_name"),
    )
    op.create_index(op.f("ix_plans_owner_id"), "plans", ["owner_id"])
    op.create_index(op.f("ix_plans_shared_course_id"), "plans", ["shared_course_id"])
    op.create_table(
        "plan_versions",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("plan_id", sa.Integer(), sa.ForeignKey("plans.id", name=op.f("fk_plan_versions_plan_id_plans"),
                                                           ondelete="CASCADE"), nullable=False),
        sa.Column("version", sa.Integer(), nullable=False),
        sa.Column("text", sa.Text(), nullable=False),
        sa.Column("canonical_json", sa.Text(), nullable=False),
        sa.Column("summary_json", sa.Text(), nullable=False),
        sa.Column("saved_by_id", sa.Integer(),
                  sa.ForeignKey("users.id", name=op.f("fk_plan_versions_saved_by_id_users"), ondelete="SET NULL"),
                  nullable=True),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_plan_versions")),
        sa.UniqueConstraint("plan_id", "version", name="uq_plan_versions_plan_version"),
    )


def downgrade() -> None:
    op.drop_table("plan_versions")
    op.drop_index(op.f("ix_plans_shared_course_id"), table_name="plans")
    op.drop_index(op.f("ix_plans_owner_id"), table_name="plans")
    op.drop_table("plans")
