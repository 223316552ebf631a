"""What a student's console measured of its own commands on a robot (the 2003 paper's table 1), for their tutor."""

from __future__ import annotations

from datetime import datetime
from typing import Any

from sqlalchemy import JSON, DateTime, ForeignKey, String, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base


class ResponseTimeReport(Base):
    """The latest response-time figures one user's console reported for one robot (replaced at each report)."""

    __tablename__ = "response_time_reports"
    __table_args__ = (UniqueConstraint("user_id", "robot_name", name="uq_response_time_reports_user_robot"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id", ondelete="CASCADE"))
    robot_name: Mapped[str] = mapped_column(String(64))
    figures: Mapped[dict[str, Any]] = mapped_column(JSON)  # {skill|drive: {total|client|robot: {...}}, delivery}
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
