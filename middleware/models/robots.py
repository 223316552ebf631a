"""The robots of the lab, managed by admins (seeded from TELELAB_ROBOTS at start)."""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import DateTime, ForeignKey, String
from sqlalchemy.orm import Mapped, mapped_column

from middleware.models.accounts import utc_now
from middleware.models.base import Base


class Robot(Base):
    """A robot the middleware may reach: a URL-safe name, a title for people, its skill server's address, and its
    kind (robots of one kind are interchangeable: same scene and model, so a pool of them serves a queue)."""

    __tablename__ = "robots"

    id: Mapped[int] = mapped_column(primary_key=True)
    name: Mapped[str] = mapped_column(String(32), unique=True)
    title: Mapped[str] = mapped_column(String(100))
    address: Mapped[str] = mapped_column(String(255))  # host:port of the gRPC skill server
    kind: Mapped[str] = mapped_column(String(32), index=True)
    farm_managed: Mapped[bool] = mapped_column(default=False)  # started by the robot farm for its pool
    scene: Mapped[str | None] = mapped_column(String(64))  # the farm runs it in this scene (farm_managed only)
    enabled: Mapped[bool] = mapped_column(default=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class RobotKindSetting(Base):
    """What an admin chose for every robot of one kind: the camera panel's default picture, the robot's JPEG video
    ("video") or the view drawn by the browser from the scene and the odometry pose ("drawn")."""

    __tablename__ = "robot_kind_settings"

    kind: Mapped[str] = mapped_column(String(32), primary_key=True)
    camera_picture: Mapped[str] = mapped_column(String(8), default="video")
    updated_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)


class RobotMaintenance(Base):
    """One maintenance action a tutor or an admin took on a robot from its health page (a restart, a return to the
    dock, a cleared map), with what came of it: the robot's maintenance log."""

    __tablename__ = "robot_maintenance"

    id: Mapped[int] = mapped_column(primary_key=True)
    robot_name: Mapped[str] = mapped_column(String(64), index=True)
    actor_id: Mapped[int | None] = mapped_column(ForeignKey("users.id", ondelete="SET NULL"), nullable=True)
    action: Mapped[str] = mapped_column(String(16))
    outcome: Mapped[str] = mapped_column(String(500))
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True), default=utc_now)
