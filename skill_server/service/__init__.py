"""The one gRPC adapter: the Robot servicer (robot_service.py) and proto <-> domain conversion (convert.py)."""

from __future__ import annotations

from skill_server.service.robot_service import RobotService

__all__ = ["RobotService"]
