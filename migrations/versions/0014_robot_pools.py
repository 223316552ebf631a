"""robot pools: each robot has a kind, users queue for any robot of a kind, and bookings may name a kind;
a class session's scene, and the robot each experimental attempt runs on (a student's own one in class)

Revision ID: 0014
Revises: 0013
Create Date: 2026-11-25
"""

from __future__ import annotations

import re

import sqlalchemy as sa
from alembic import op

revision = "0014"
down_revision = "0013"
branch_labels = None
depends_on = None


def _default_kind(name: str) -> str:
    # The same rule as middleware.robots.catalog.default_kind, frozen here as migrations must be.
    return re.sub(r"-\d+$", "", name) or name


def upgrade() -> None:
    with op.batch_alter_table("robots") as batch:
        batch.add_column(sa.Column("kind", sa.String(length=32), nullable=False, server_default=""))
        batch.add_column(sa.Column("farm_managed", sa.Boolean(), nullable=False, server_default=sa.false()))
        batch.add_column(sa.Column("scene", sa.String(length=64), nullable=True))
    robots = sa.table("robots", sa.column("id", sa.Integer()), sa.column("name", sa.String()),
                      sa.column("kind", sa.String()))
    connection = op.get_bind()
    for robot_id, name in connection.execute(sa.select(robots.c.id, robots.c.name)).all():
        connection.execute(robots.update().where(robots.c.id == robot_id).values(kind=_default_kind(name)))
    op.create_index(op.f("ix_robots_kind"), "robots", ["kind"])
    with op.batch_alter_table("bookings") as batch:
        batch.alter_column("robot_name", existing_type=sa.String(length=32), nullable=True)
        batch.add_column(sa.Column("pool_kind", sa.String(length=32), nullable=True))
        batch.create_check_constraint("robot_or_pool", "robot_name IS NOT NULL OR pool_kind IS NOT NULL")
    op.create_index(op.f("ix_bookings_pool_kind"), "bookings", ["pool_kind"])
    op.create_table(
        "pool_queue_entries",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("kind", sa.String(length=32), nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("enqueued_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("last_seen_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(["user_id"], ["users.id"], name=op.f("fk_pool_queue_entries_user_id_users"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_pool_queue_entries")),
        sa.UniqueConstraint("kind", "user_id", name="uq_pool_queue_entries_kind_user"),
    )
    op.create_index(op.f("ix_pool_queue_entries_kind"), "pool_queue_entries", ["kind"])
    with op.batch_alter_table("class_sessions") as batch:
        batch.add_column(sa.Column("scene", sa.String(length=64), nullable=False, server_default="lab"))
        batch.add_column(sa.Column("booking_id", sa.Integer(), nullable=True))
        batch.create_foreign_key(op.f("fk_class_sessions_booking_id_bookings"), "bookings", ["booking_id"], ["id"],
                                 ondelete="SET NULL")
    with op.batch_alter_table("assessment_attempts") as batch:
        batch.add_column(sa.Column("robot_name", sa.String(length=64), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("assessment_attempts") as batch:
        batch.drop_column("robot_name")
    with op.batch_alter_table("class_sessions") as batch:
        batch.drop_constraint(op.f("fk_class_sessions_booking_id_bookings"), type_="foreignkey")
        batch.drop_column("booking_id")
        batch.drop_column("scene")
    op.drop_table("pool_queue_entries")
    op.drop_index(op.f("ix_bookings_pool_kind"), table_name="bookings")
    op.execute("DELETE FROM bookings WHERE robot_name IS NULL")
    with op.batch_alter_table("bookings") as batch:
        batch.drop_constraint("robot_or_pool", type_="check")
        batch.drop_column("pool_kind")
        batch.alter_column("robot_name", existing_type=sa.String(length=32), nullable=False)
    op.drop_index(op.f("ix_robots_kind"), table_name="robots")
    with op.batch_alter_table("robots") as batch:
        batch.drop_column("scene")
        batch.drop_column("farm_managed")
        batch.drop_column("kind")
