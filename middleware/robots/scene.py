"""The robot's static world (GetScene) as the browser's 3D views read it: plain JSON, short names, lists for
vectors and colours. The content is the skill server's; nothing here adds to it or leaves anything out."""

from __future__ import annotations

from protos.telelab.v1 import robot_pb2


def _kind(value: int) -> str:
    """'grid' for FLOOR_PATCH_KIND_GRID, and so on ('unspecified' for a value this middleware does not know)."""
    try:
        return robot_pb2.FloorPatchKind.Name(value).removeprefix("FLOOR_PATCH_KIND_").lower()
    except ValueError:
        return "unspecified"


def _shape(value: int) -> str:
    try:
        return robot_pb2.PartShape.Name(value).removeprefix("PART_SHAPE_").lower()
    except ValueError:
        return "unspecified"


def _rgba(colour: robot_pb2.Rgba) -> list[float]:
    return [colour.r, colour.g, colour.b, colour.a]


def _patch(patch: robot_pb2.FloorPatch) -> dict[str, object]:
    return {"center_x_m": patch.center_x_m, "center_y_m": patch.center_y_m, "half_x_m": patch.half_x_m,
            "half_y_m": patch.half_y_m, "top_z_m": patch.top_z_m, "rgba": _rgba(patch.colour),
            "kind": _kind(patch.kind)}


def scene_dict(scene: robot_pb2.SceneDescription) -> dict[str, object]:
    """The scene as JSON-ready data (robot_pb2's comments say what each field means)."""
    camera, laser, track = scene.camera, scene.laser, scene.track
    return {
        "version": scene.version,
        "scene_name": scene.scene_name,
        "floor": _patch(scene.floor),
        "marks": [_patch(mark) for mark in scene.marks],
        "blocks": [{"name": b.name, "center_x_m": b.center_x_m, "center_y_m": b.center_y_m, "half_x_m": b.half_x_m,
                    "half_y_m": b.half_y_m, "height_m": b.height_m, "yaw_rad": b.yaw_rad, "rgba": _rgba(b.colour)}
                   for b in scene.blocks],
        "cylinders": [{"name": c.name, "center_x_m": c.center_x_m, "center_y_m": c.center_y_m,
                       "radius_m": c.radius_m, "height_m": c.height_m, "rgba": _rgba(c.colour)}
                      for c in scene.cylinders],
        "track": {
            "a": [track.a_x_m, track.a_y_m], "b": [track.b_x_m, track.b_y_m], "round_trip": track.round_trip,
            "arrival_radius_m": track.arrival_radius_m,
            "lines": [[line.x1_m, line.y1_m, line.x2_m, line.y2_m, line.half_width_m] for line in track.lines],
        } if scene.HasField("track") else None,
        "spawn": {"x_m": scene.spawn.x_m, "y_m": scene.spawn.y_m, "theta_rad": scene.spawn.theta_rad},
        "body_radius_m": scene.body_radius_m,
        "robot_parts": [{"link": part.link, "shape": _shape(part.shape),
                         "size_m": [part.size_x_m, part.size_y_m, part.size_z_m],
                         "position_m": [part.position_m.x, part.position_m.y, part.position_m.z],
                         "orientation_xyzw": [part.orientation.x, part.orientation.y, part.orientation.z,
                                              part.orientation.w],
                         "rgba": _rgba(part.colour)} for part in scene.robot_parts],
        "camera": {
            "width_px": camera.width_px, "height_px": camera.height_px, "hfov_deg": camera.hfov_deg,
            "vfov_deg": camera.vfov_deg, "near_m": camera.near_m, "far_m": camera.far_m,
            "mount_forward_m": camera.mount_forward_m, "mount_height_m": camera.mount_height_m,
            "mount_pitch_rad": camera.mount_pitch_rad,
            "light_direction": [camera.light_direction.x, camera.light_direction.y, camera.light_direction.z],
            "light_ambient": camera.light_ambient, "light_diffuse": camera.light_diffuse,
            "light_specular": camera.light_specular, "specular_exponent": camera.specular_exponent,
            "background_rgba": _rgba(camera.background),
            "sample_offset_x_px": camera.sample_offset_x_px, "sample_offset_y_px": camera.sample_offset_y_px,
        },
        "laser": {"angle_min_rad": laser.angle_min_rad, "angle_max_rad": laser.angle_max_rad,
                  "beam_count": laser.beam_count, "min_range_m": laser.min_range_m, "max_range_m": laser.max_range_m,
                  "height_m": laser.height_m},
        "sonar": {"mount_radius_m": scene.sonar.mount_radius_m, "height_m": scene.sonar.height_m,
                  "sonars": [{"mount_angle_rad": s.mount_angle_rad, "cone_half_angle_rad": s.cone_half_angle_rad,
                              "min_range_m": s.min_range_m, "max_range_m": s.max_range_m}
                             for s in scene.sonar.sonars]},
        "room_cameras": [{"id": c.id, "title": c.title, "position_m": [c.x_m, c.y_m, c.z_m], "pan_rad": c.pan_rad,
                          "tilt_rad": c.tilt_rad, "hfov_deg": c.hfov_deg, "pan_range_rad": c.pan_range_rad,
                          "tilt_range_rad": [c.min_tilt_rad, c.max_tilt_rad],
                          "hfov_range_deg": [c.min_hfov_deg, c.max_hfov_deg]} for c in scene.room_cameras],
    }
