"""Proto <-> domain translation for teleperception: the evidence grid's layers and the raw readings."""

from __future__ import annotations

from protos.telelab.v1 import robot_pb2
from skill_server.errors import InvalidParameter
from skill_server.robot import EvidenceState, PerceptionScan, Pose2D
from skill_server.service.convert import grid_to_proto, pose_to_proto

_SENSORS = {robot_pb2.EVIDENCE_SENSOR_UNSPECIFIED: ("sonar", "laser"), robot_pb2.EVIDENCE_SENSOR_SONAR: ("sonar",),
            robot_pb2.EVIDENCE_SENSOR_LASER: ("laser",)}
_PARTS = {robot_pb2.EVIDENCE_PART_UNSPECIFIED: ("static", "moving"), robot_pb2.EVIDENCE_PART_STATIC: ("static",),
          robot_pb2.EVIDENCE_PART_MOVING: ("moving",)}
_PART_TO_PROTO = {"static": robot_pb2.EVIDENCE_PART_STATIC, "moving": robot_pb2.EVIDENCE_PART_MOVING}


def layers_from_proto(request: robot_pb2.GetEvidenceGridRequest) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The sensors and parts a request asks for; an unknown enum value is InvalidParameter naming its field."""
    sensors, parts = _SENSORS.get(request.sensor), _PARTS.get(request.part)
    if sensors is None:
        raise InvalidParameter("sensor", "sensor must be EVIDENCE_SENSOR_SONAR, _LASER or _UNSPECIFIED (both)")
    if parts is None:
        raise InvalidParameter("part", "part must be EVIDENCE_PART_STATIC, _MOVING or _UNSPECIFIED (both)")
    return sensors, parts


def evidence_to_proto(state: EvidenceState, odometry: Pose2D) -> robot_pb2.EvidenceGrid:
    """The chosen layers as an OccupancyGrid, with the counts and the odometry pose now."""
    return robot_pb2.EvidenceGrid(
        grid=grid_to_proto(state.view),
        sonar_scans=state.scans_by_sensor["sonar"], laser_scans=state.scans_by_sensor["laser"],
        static_scans=state.scans_by_part["static"], moving_scans=state.scans_by_part["moving"],
        odometry=pose_to_proto(odometry),
        accumulating=state.accumulating, version=state.version,
    )


def scans_to_proto(scans: list[PerceptionScan]) -> robot_pb2.PerceptionReadings:
    """The raw readings kept."""
    return robot_pb2.PerceptionReadings(scans=[robot_pb2.PerceptionScan(
        index=scan.index, capture_unix_s=scan.capture_unix_s, sim_time_s=scan.sim_time_s,
        odometry=pose_to_proto(scan.odometry),
        part=_PART_TO_PROTO[scan.part], sonar_ranges_m=scan.sonar_ranges_m, laser_ranges_m=scan.laser_ranges_m,
    ) for scan in scans])
