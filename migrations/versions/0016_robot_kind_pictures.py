"""per robot kind, the camera panel's default picture (the robot's video or the view drawn by the browser)

Revision ID: 0016
Revises: 0015
Create Date: 2026-11-26
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0016"
down_revision = "0015"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "robot_kind_settings",
        sa.Column("kind", sa.String(length=32), nullable=False),
        sa.Column("camera_picture", sa.String(length=8), nullable=False),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.PrimaryKeyConstraint("kind", name=op.f("pk_robot_kind_settings")),
    )


def downgrade() -> None:
    op.drop_table("robot_kind_settings")
