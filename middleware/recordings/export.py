"""A recording read back for people: the replay page's data (decoded channels on one clock), a merged MCAP file,
and a CSV per channel. Whoever may not see the ground truth gets neither its channel nor the truth inside the
localization messages, in any of them."""

from __future__ import annotations

import io
import json
import math
from collections.abc import Iterable, Iterator

from google.protobuf.json_format import MessageToDict

from middleware.recordings import channels, files
from middleware.robots.scene import scene_dict
from protos.telelab.v1 import robot_pb2

LASER_EVERY_S = 0.5
CSV_CHANNELS = ("odometry", "ground_truth", "sonar", "laser", "localization", "commands", "goals")
_TOPIC_OF = {name: f"/{name}" for name in CSV_CHANNELS}
_GOAL_STATUS = {value.number: value.name.removeprefix("GOAL_STATUS_").lower()
                for value in robot_pb2.DESCRIPTOR.enum_types_by_name["GoalStatus"].values}


def allowed(messages: Iterable[files.Recorded], truth: bool) -> Iterator[files.Recorded]:
    """The messages the viewer may have: without truth, no /ground_truth and localization with its truth cleared."""
    for message in messages:
        if message.topic in channels.TRUTH_TOPICS and not truth:
            continue
        if message.topic == channels.LOCALIZATION and not truth:
            update = robot_pb2.LocalizationUpdate()
            update.ParseFromString(message.data)
            for name in ("ground_truth", "position_error_m", "heading_error_rad", "odometry_position_error_m",
                         "odometry_heading_error_rad"):
                update.ClearField(name)
            yield files.Recorded(message.topic, message.log_time_ns, update.SerializeToString())
            continue
        yield message


def merged_mcap(messages: Iterable[files.Recorded], metadata: dict[str, str]) -> bytes:
    """One MCAP file of the messages (every part merged, in log-time order), with its summary and index."""
    out = io.BytesIO()
    writer = files.PartWriter(out, metadata, chunk_bytes=1024 * 1024)
    for message in messages:
        writer.write(message.topic, message.decode(), message.log_time_ns)
    writer.finish()
    return out.getvalue()


def _r(value: float, digits: int = 4) -> float:
    return round(float(value), digits)


def replay_data(messages: list[files.Recorded], truth: bool, from_s: float = 0.0,
                to_s: float | None = None, t0_ns: int | None = None,
                laser_every_s: float = LASER_EVERY_S) -> dict[str, object]:
    """The replay page's data: times in seconds from the recording's first message (t0_ns), from_s to to_s."""
    visible = list(allowed(messages, truth))
    t0 = t0_ns if t0_ns is not None else visible[0].log_time_ns if visible else 0
    data: dict[str, list[object]] = {"odometry": [], "ground_truth": [], "sonar": [], "laser": [],
                                     "localization": [], "commands": [], "goals": [], "camera": []}
    camera_index = 0
    last_laser_t = -math.inf
    scene: dict[str, object] | None = None
    info: dict[str, object] | None = None
    end_s = 0.0
    for message in visible:
        t = (message.log_time_ns - t0) / 1e9
        end_s = max(end_s, t)
        if message.topic == channels.SCENE and scene is None:
            scene = scene_dict(message.decode())  # type: ignore[arg-type]
            continue
        if message.topic == channels.ROBOT_INFO and info is None:
            robot_info = message.decode()
            assert isinstance(robot_info, robot_pb2.RobotInfo)
            info = {"sonar_angles_rad": [s.mount_angle_rad for s in robot_info.sonars],
                    "sonar_max_m": [s.max_range_m for s in robot_info.sonars],
                    "laser": MessageToDict(robot_info.laser, preserving_proto_field_name=True)}
            continue
        if message.topic == channels.CAMERA:
            if from_s <= t and (to_s is None or t <= to_s):
                data["camera"].append([round(t, 3), camera_index])  # the frame's own URL names the index
            camera_index += 1
            continue
        if t < from_s or (to_s is not None and t > to_s):
            continue
        if message.topic == channels.LASER:
            if t - last_laser_t < laser_every_s:
                continue  # the replay draws the laser 2 times a second (the CSV and MCAP keep every scan)
            last_laser_t = t
        _add(data, message, round(t, 3))
    return {"t0_unix_s": t0 / 1e9, "duration_s": round(end_s, 3), "truth": truth, "scene": scene, "info": info,
            **data}


def camera_frame(messages: list[files.Recorded], index: int) -> bytes | None:
    """The JPEG of the recording's index-th camera frame, or None."""
    frames = [m for m in messages if m.topic == channels.CAMERA]
    if not 0 <= index < len(frames):
        return None
    frame = frames[index].decode()
    assert isinstance(frame, robot_pb2.CameraFrame)
    return frame.jpeg


def _add(data: dict[str, list[object]], message: files.Recorded, t: float) -> None:
    decoded = message.decode()
    if isinstance(decoded, robot_pb2.Odometry):
        p = decoded.pose
        data["odometry"].append([t, _r(p.x_m), _r(p.y_m), _r(p.theta_rad), _r(decoded.linear_mps),
                                 _r(decoded.angular_radps)])
    elif message.topic == channels.GROUND_TRUTH and isinstance(decoded, robot_pb2.Pose2D):
        data["ground_truth"].append([t, _r(decoded.x_m), _r(decoded.y_m), _r(decoded.theta_rad)])
    elif isinstance(decoded, robot_pb2.SonarReading):
        data["sonar"].append([t, *[_r(r, 3) for r in decoded.ranges_m]])
    elif isinstance(decoded, robot_pb2.LaserScan):
        data["laser"].append([t, _r(decoded.angle_min_rad), _r(decoded.angle_increment_rad, 6),
                              [_r(r, 3) for r in decoded.ranges_m]])
    elif isinstance(decoded, robot_pb2.LocalizationUpdate):
        e = decoded.estimate
        data["localization"].append([t, _r(e.x_m), _r(e.y_m), _r(e.theta_rad), decoded.converged])
    elif isinstance(decoded, channels.CommandRecord):
        data["commands"].append({
            "t": t, "sequence": decoded.sequence, "source": decoded.source,  # type: ignore[attr-defined]
            "action": decoded.action, "linear_mps": _r(decoded.linear_mps),  # type: ignore[attr-defined]
            "angular_radps": _r(decoded.angular_radps), "skill": decoded.skill,  # type: ignore[attr-defined]
            "plan_name": decoded.plan_name, "accepted": decoded.accepted,  # type: ignore[attr-defined]
            "outcome": decoded.outcome})  # type: ignore[attr-defined]
    elif isinstance(decoded, robot_pb2.GoalState):
        data["goals"].append({"t": t, "goal_id": decoded.goal_id, "skill": decoded.skill,
                              "status": _GOAL_STATUS.get(decoded.status, "unknown"), "message": decoded.message})


def channel_csv(data: dict[str, object], channel: str) -> str:
    """One channel of replay_data() as CSV text (a header naming units, a row per message)."""
    rows = data.get(channel) or []
    assert isinstance(rows, list)
    out = io.StringIO()
    if channel == "odometry":
        out.write("t_s,x_m,y_m,theta_rad,linear_mps,angular_radps\n")
        out.writelines(",".join(str(v) for v in row) + "\n" for row in rows)
    elif channel == "ground_truth":
        out.write("t_s,x_m,y_m,theta_rad\n")
        out.writelines(",".join(str(v) for v in row) + "\n" for row in rows)
    elif channel == "sonar":
        width = max((len(row) - 1 for row in rows), default=0)
        out.write("t_s," + ",".join(f"sonar_{i}_m" for i in range(width)) + "\n")
        out.writelines(",".join(str(v) for v in row) + "\n" for row in rows)
    elif channel == "laser":
        out.write("t_s,beam,angle_rad,range_m\n")
        for t, angle_min, step, ranges in rows:
            out.writelines(f"{t},{i},{round(angle_min + i * step, 4)},{r}\n" for i, r in enumerate(ranges))
    elif channel == "localization":
        out.write("t_s,estimate_x_m,estimate_y_m,estimate_theta_rad,converged\n")
        out.writelines(",".join(str(v) for v in row) + "\n" for row in rows)
    else:
        fields = ("t", "sequence", "source", "action", "linear_mps", "angular_radps", "skill", "plan_name",
                  "accepted", "outcome") if channel == "commands" else ("t", "goal_id", "skill", "status",
                                                                         "message")
        out.write(",".join("t_s" if f == "t" else f for f in fields) + "\n")
        for row in rows:
            assert isinstance(row, dict)
            out.write(",".join(_csv_cell(row.get(f, "")) for f in fields) + "\n")
    return out.getvalue()


def _csv_cell(value: object) -> str:
    text = json.dumps(value) if isinstance(value, str) else str(value).lower() if isinstance(value, bool) else str(
        value)
    if isinstance(value, str) and text[1:2] in "=+-@":
        text = '"\'' + text[1:]  # a formula-looking text stays text in a spreadsheet
    return text
