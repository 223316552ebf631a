"""teaching topics: tours and lessons carry topics, so a student's weak topics can recommend them

Revision ID: 0008
Revises: 0007
Create Date: 2026-11-29
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0008"
down_revision = "0007"
branch_labels = None
depends_on = None

# The demo content's topics (middleware/teaching/demo_content.py), for databases seeded before this revision.
DEMO_TOPICS = {
    ("tours", "direct-control"): "direct control, odometry",
    ("tours", "go-to-goal"): "navigation, path planning",
    ("tours", "wall-following"): "sensors, sonar, wall following",
    ("tours", "localization"): "laser, localization, sensors",
    ("lessons", "first-moves"): "direct control, navigation, odometry",
}


def upgrade() -> None:
    for table in ("tours", "lessons"):
        with op.batch_alter_table(table, schema=None) as batch_op:
            batch_op.add_column(sa.Column("topics", sa.Text(), server_default="", nullable=False))
    for (table, slug), topics in DEMO_TOPICS.items():
        op.execute(sa.text(f"UPDATE {table} SET topics = :topics WHERE slug = :slug AND topics = ''")
                   .bindparams(topics=topics, slug=slug))


def downgrade() -> None:
    for table in ("lessons", "tours"):
        with op.batch_alter_table(table, schema=None) as batch_op:
            batch_op.drop_column("topics")
