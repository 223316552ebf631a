"""The one gRPC adapter, split by concern: the Robot servicer, goal RPCs, and proto <-> domain conversion."""

from __future__ import annotations

from skill_server.service.robot_service import RobotService, SimTimePacer

__all__ = ["RobotService", "SimTimePacer"]
