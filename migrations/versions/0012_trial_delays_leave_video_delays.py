"""trial delays leave video_delays: an open trial's delay is read from the trial, on its robot only

Trials used to copy their delay into the user's video_delays row (set_by_id NULL), where it applied to every
robot, and wrote 0 there when they ended. Those copies are removed; tutors' delays (set_by_id set) stay.

Revision ID: 0012
Revises: 0011
Create Date: 2026-11-23
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0012"
down_revision = "0011"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.execute(sa.text("DELETE FROM video_delays WHERE set_by_id IS NULL"))


def downgrade() -> None:
    pass  # the copies are not needed: open trials' delays are read from the trials
