"""usage analytics and xAPI (issue 30): queue waits, robot outages, lessons watched and tours followed, the xAPI
outbox

Revision ID: 0029
Revises: 0028
Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0029"
down_revision = "0028"
branch_labels = None
depends_on = None


def _user_fk(table: str) -> sa.ForeignKeyConstraint:
    return sa.ForeignKeyConstraint(["user_id"], ["users.id"], name=op.f(f"fk_{table}_user_id_users"),
                                   ondelete="CASCADE")


def upgrade() -> None:
    op.create_table(
        "analytics_queue_waits",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("robot_name", sa.String(64), nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("waited_from", sa.DateTime(timezone=True), nullable=False),
        sa.Column("granted_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("wait_s", sa.Float(), nullable=False),
        sa.CheckConstraint("wait_s >= 0", name=op.f("ck_analytics_queue_waits_wait_not_negative")),
        _user_fk("analytics_queue_waits"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_analytics_queue_waits")),
    )
    op.create_index("ix_analytics_queue_waits_user_id", "analytics_queue_waits", ["user_id"])
    op.create_index("ix_analytics_queue_waits_granted_at", "analytics_queue_waits", ["granted_at"])
    op.create_table(
        "analytics_robot_outages",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("robot_name", sa.String(64), nullable=False),
        sa.Column("started_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("ended_at", sa.DateTime(timezone=True), nullable=True),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_analytics_robot_outages")),
    )
    op.create_index("ix_analytics_robot_outages_robot_started", "analytics_robot_outages", ["robot_name", "started_at"])
    op.create_table(
        "analytics_learning_events",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("kind", sa.String(16), nullable=False),
        sa.Column("object_id", sa.Integer(), nullable=False),
        sa.Column("at", sa.DateTime(timezone=True), nullable=False),
        sa.CheckConstraint("kind IN ('lesson_watched', 'tour_followed')",
                           name=op.f("ck_analytics_learning_events_kind_known")),
        _user_fk("analytics_learning_events"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_analytics_learning_events")),
    )
    op.create_index("ix_analytics_learning_events_user_kind", "analytics_learning_events",
                    ["user_id", "kind", "object_id"])
    op.create_index("ix_analytics_learning_events_at", "analytics_learning_events", ["at"])
    op.create_table(
        "xapi_outbox",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("statement_id", sa.String(36), nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("statement_json", sa.Text(), nullable=False),
        sa.Column("status", sa.String(16), nullable=False),
        sa.Column("tries", sa.Integer(), nullable=False),
        sa.Column("next_try_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("claimed_by", sa.String(96), nullable=True),
        sa.Column("claimed_until", sa.DateTime(timezone=True), nullable=True),
        sa.Column("last_error", sa.Text(), nullable=True),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("sent_at", sa.DateTime(timezone=True), nullable=True),
        sa.CheckConstraint("status IN ('pending', 'sent', 'failed')", name=op.f("ck_xapi_outbox_status_known")),
        _user_fk("xapi_outbox"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_xapi_outbox")),
        sa.UniqueConstraint("statement_id", name=op.f("uq_xapi_outbox_statement_id")),
    )
    op.create_index("ix_xapi_outbox_due", "xapi_outbox", ["status", "next_try_at"])
    op.create_index("ix_xapi_outbox_user_id", "xapi_outbox", ["user_id"])


def downgrade() -> None:
    op.drop_index("ix_xapi_outbox_user_id", table_name="xapi_outbox")
    op.drop_index("ix_xapi_outbox_due", table_name="xapi_outbox")
    op.drop_table("xapi_outbox")
    op.drop_index("ix_analytics_learning_events_at", table_name="analytics_learning_events")
    op.drop_index("ix_analytics_learning_events_user_kind", table_name="analytics_learning_events")
    op.drop_table("analytics_learning_events")
    op.drop_index("ix_analytics_robot_outages_robot_started", table_name="analytics_robot_outages")
    op.drop_table("analytics_robot_outages")
    op.drop_index("ix_analytics_queue_waits_granted_at", table_name="analytics_queue_waits")
    op.drop_index("ix_analytics_queue_waits_user_id", table_name="analytics_queue_waits")
    op.drop_table("analytics_queue_waits")
