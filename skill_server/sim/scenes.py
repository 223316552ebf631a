"""Scenes: rooms, walls, obstacles and floor markings, registered by name and described as data."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from skill_server.errors import UnknownScene
from skill_server.sim.floor_line import FloorLine, paint_patches
from skill_server.sim.geometry import Pose2D
from skill_server.sim.track_monitor import BorderLine, TrackSpec

Rgba = tuple[float, float, float, float]

FLOOR_THICKNESS_M = 0.05
MARK_THICKNESS_M = 0.002


@dataclass(frozen=True)
class BoxObstacle:
    """A solid box standing on the floor (walls are boxes too)."""

    name: str
    center_x_m: float
    center_y_m: float
    half_x_m: float
    half_y_m: float
    height_m: float
    rgba: Rgba
    yaw_rad: float = 0.0


@dataclass(frozen=True)
class CylinderObstacle:
    """A solid upright cylinder standing on the floor."""

    name: str
    center_x_m: float
    center_y_m: float
    radius_m: float
    height_m: float
    rgba: Rgba


# What a floor mark is, for views that treat them apart (a track's border lines, the grid, plain paint).
MARK_KINDS = ("paint", "grid", "track_line", "track_point")


@dataclass(frozen=True)
class FloorMark:
    """A coloured patch painted on the floor: seen by the camera, invisible to physics and range sensors."""

    center_x_m: float
    center_y_m: float
    half_x_m: float
    half_y_m: float
    rgba: Rgba
    kind: str = "paint"  # one of MARK_KINDS


@dataclass(frozen=True)
class FloorPatch:
    """A flat upward-facing rectangle as the world builds it: the floor itself or one painted mark on it."""

    center_x_m: float
    center_y_m: float
    half_x_m: float
    half_y_m: float
    top_z_m: float  # [m] height of the visible face above the floor's top (0 for the floor)
    rgba: Rgba
    kind: str  # "floor", or the mark's kind


@dataclass(frozen=True)
class SceneBox:
    """An obstacle's footprint as a box, as RobotInfo.scene_boxes reports it for maps."""

    name: str
    center_x_m: float
    center_y_m: float
    half_x_m: float
    half_y_m: float
    yaw_rad: float = 0.0


@dataclass(frozen=True)
class RoomCamera:
    """A pan-tilt-zoom camera mounted in the room (the 2003 lab's), seeing the robot from outside: where it hangs,
    where it looks at rest (pan from +x, counter-clockwise; tilt below the horizon) and its field at rest. A viewer
    turns and zooms their own copy of the view; the limits are the mount's."""

    id: str
    title: str
    x_m: float
    y_m: float
    z_m: float
    pan_rad: float
    tilt_rad: float
    hfov_deg: float = 60.0
    pan_range_rad: float = math.radians(75.0)  # either way from rest
    min_tilt_rad: float = math.radians(5.0)
    max_tilt_rad: float = math.radians(80.0)
    min_hfov_deg: float = 15.0
    max_hfov_deg: float = 75.0


def corner_camera(x_m: float, y_m: float, z_m: float, title: str = "Room camera") -> RoomCamera:
    """A camera at (x, y, z) aimed at the room's centre."""
    return RoomCamera("room", title, x_m, y_m, z_m, math.atan2(-y_m, -x_m),
                      math.atan2(z_m, math.hypot(x_m, y_m)))


@dataclass(frozen=True)
class SceneSpec:
    """Everything a world needs to build a scene."""

    name: str
    floor_half_x_m: float
    floor_half_y_m: float
    floor_rgba: Rgba = (0.55, 0.55, 0.52, 1.0)
    boxes: tuple[BoxObstacle, ...] = ()
    cylinders: tuple[CylinderObstacle, ...] = ()
    marks: tuple[FloorMark, ...] = ()
    spawn: Pose2D = field(default_factory=Pose2D)
    track: TrackSpec | None = None  # track scenes: A, B and border lines the track monitor watches
    room_cameras: tuple[RoomCamera, ...] = ()
    line: FloorLine | None = None  # a closed line of tape the line sensor reads (its paint is among the marks)

    def scene_boxes(self) -> list[SceneBox]:
        """Walls and obstacles as boxes; a cylinder is reported as its bounding square."""
        boxes = [SceneBox(b.name, b.center_x_m, b.center_y_m, b.half_x_m, b.half_y_m, b.yaw_rad) for b in self.boxes]
        boxes += [SceneBox(c.name, c.center_x_m, c.center_y_m, c.radius_m, c.radius_m) for c in self.cylinders]
        return boxes


_SCENES: dict[str, Callable[[], SceneSpec]] = {}


def register_scene(name: str, factory: Callable[[], SceneSpec]) -> None:
    """Makes a scene available to worlds by name (re-registering a name replaces it)."""
    _SCENES[name] = factory


def known_scenes() -> list[str]:
    """Names of every registered scene, sorted."""
    return sorted(_SCENES)


def get_scene(name: str) -> SceneSpec:
    """The scene registered under name, or UnknownScene listing the known ones."""
    try:
        factory = _SCENES[name]
    except KeyError:
        raise UnknownScene(name, list(_SCENES)) from None
    return factory()


def room_walls(half_x_m: float, half_y_m: float, height_m: float = 1.0, thickness_m: float = 0.1) -> list[BoxObstacle]:
    """Four walls, each its own colour so a turn shows in the camera, whose inner faces bound the room."""
    half_t = thickness_m / 2.0
    return [
        BoxObstacle(
            "wall_east",
            half_x_m + half_t,
            0.0,
            half_t,
            half_y_m + thickness_m,
            height_m,
            (0.80, 0.25, 0.20, 1.0),
        ),
        BoxObstacle(
            "wall_west",
            -half_x_m - half_t,
            0.0,
            half_t,
            half_y_m + thickness_m,
            height_m,
            (0.20, 0.40, 0.80, 1.0),
        ),
        BoxObstacle("wall_north", 0.0, half_y_m + half_t, half_x_m, half_t, height_m, (0.25, 0.65, 0.30, 1.0)),
        BoxObstacle("wall_south", 0.0, -half_y_m - half_t, half_x_m, half_t, height_m, (0.90, 0.75, 0.20, 1.0)),
    ]


def _grid_marks(
    half_x_m: float, half_y_m: float, spacing_m: float = 1.0, half_width_m: float = 0.015
) -> list[FloorMark]:
    grey = (0.92, 0.92, 0.92, 1.0)
    marks = []
    for i in range(-int(half_x_m / spacing_m), int(half_x_m / spacing_m) + 1):
        marks.append(FloorMark(i * spacing_m, 0.0, half_width_m, half_y_m, grey, "grid"))
    for j in range(-int(half_y_m / spacing_m), int(half_y_m / spacing_m) + 1):
        marks.append(FloorMark(0.0, j * spacing_m, half_x_m, half_width_m, grey, "grid"))
    return marks


def lab_scene() -> SceneSpec:
    """The default scene: an 8 m x 6 m room with coloured walls, a few obstacles and a painted floor."""
    half_x, half_y = 4.0, 3.0
    marks = _grid_marks(half_x, half_y)
    marks += [
        # Tiles and a track give the camera something to see move.
        FloorMark(1.5, 1.5, 0.35, 0.35, (0.95, 0.55, 0.10, 1.0)),
        FloorMark(-2.5, -1.5, 0.35, 0.35, (0.55, 0.20, 0.75, 1.0)),
        FloorMark(-1.0, 2.0, 0.35, 0.35, (0.10, 0.70, 0.75, 1.0)),
        FloorMark(2.0, 0.0, 1.5, 0.04, (0.85, 0.15, 0.15, 1.0)),  # a red lane straight ahead of the spawn
        FloorMark(0.0, 0.0, 0.30, 0.30, (0.15, 0.35, 0.85, 1.0)),  # the home square under the spawn
        FloorMark(-3.0, 2.2, 0.6, 0.04, (0.95, 0.90, 0.15, 1.0)),
    ]
    marks += tape_marks(LAB_LINE)  # painted last: the tape crosses the red lane
    return SceneSpec(
        name="lab",
        floor_half_x_m=half_x,
        floor_half_y_m=half_y,
        boxes=(
            *room_walls(half_x, half_y),
            BoxObstacle("crate", 2.5, 1.4, 0.30, 0.30, 0.50, (0.60, 0.40, 0.20, 1.0)),
            BoxObstacle("cabinet", -2.2, 1.6, 0.40, 0.25, 0.80, (0.30, 0.30, 0.35, 1.0)),
            BoxObstacle("bench", -1.0, -2.0, 0.60, 0.25, 0.45, (0.75, 0.75, 0.60, 1.0), yaw_rad=0.0),
        ),
        cylinders=(CylinderObstacle("pillar", 1.8, -1.5, 0.25, 1.0, (0.85, 0.85, 0.85, 1.0)),),
        marks=tuple(marks),
        spawn=Pose2D(0.0, 0.0, 0.0),
        room_cameras=(corner_camera(-half_x + 0.2, -half_y + 0.2, 2.4),),
        line=LAB_LINE,
    )


# The lab's line of black tape: a 3 m x 1.6 m rounded rectangle in the open middle, clear of the grid lines and at
# least 0.25 m from every obstacle for the robot's body (the follow-the-line exercise).
LAB_LINE = FloorLine(x_min_m=-1.7, x_max_m=1.3, y_min_m=-0.8, y_max_m=0.8, corner_radius_m=0.45)


def tape_marks(line: FloorLine) -> list[FloorMark]:
    """The line's tape as floor marks."""
    return [FloorMark(x, y, hx, hy, line.rgba) for x, y, hx, hy in paint_patches(line)]


def empty_scene() -> SceneSpec:
    """A bare 20 m x 20 m floor with a grid, for kinematics tests."""
    return SceneSpec(name="empty", floor_half_x_m=10.0, floor_half_y_m=10.0, marks=tuple(_grid_marks(10.0, 10.0)))


WHITE_LINE = (0.97, 0.97, 0.97, 1.0)
POINT_A_RGBA = (0.15, 0.35, 0.85, 1.0)
POINT_B_RGBA = (0.95, 0.55, 0.10, 1.0)


def _line_mark(line: BorderLine) -> FloorMark:
    """An axis-aligned white line as a floor mark."""
    half = line.half_width_m
    return FloorMark((line.x1_m + line.x2_m) / 2, (line.y1_m + line.y2_m) / 2,
                     abs(line.x2_m - line.x1_m) / 2 + half, abs(line.y2_m - line.y1_m) / 2 + half, WHITE_LINE,
                     "track_line")


def _point_marks(track: TrackSpec) -> list[FloorMark]:
    return [FloorMark(track.a_x_m, track.a_y_m, 0.30, 0.30, POINT_A_RGBA, "track_point"),
            FloorMark(track.b_x_m, track.b_y_m, 0.30, 0.30, POINT_B_RGBA, "track_point")]


def track_a_scene() -> SceneSpec:
    """Thesis track A: from A to B (5 m straight ahead) and back to A, as fast as possible."""
    half_x, half_y = 4.0, 2.0
    track = TrackSpec(a_x_m=-2.5, a_y_m=0.0, b_x_m=2.5, b_y_m=0.0, round_trip=True)
    marks = [*_grid_marks(half_x, half_y), *_point_marks(track)]
    return SceneSpec(name="course-A", floor_half_x_m=half_x, floor_half_y_m=half_y,
                     boxes=tuple(room_walls(half_x, half_y)), marks=tuple(marks),
                     spawn=Pose2D(track.a_x_m, track.a_y_m, 0.0), track=track,
                     room_cameras=(corner_camera(0.0, -half_y + 0.2, 2.6),))


def track_b_lines(w: float = 0.6) -> tuple[BorderLine, ...]:
    """The borders of an S-shaped corridor 2w wide: east 3 m from A, north 3 m, east 3 m to B (A at -3,-1.5)."""
    ox, oy = -3.0, -1.5  # A; the centre line is A -> (0,-1.5) -> (0,1.5) -> B (3,1.5)
    segments = [
        (ox - w, oy - w, ox - w, oy + w),          # behind A
        (ox - w, oy - w, ox + 3 + w, oy - w),      # south of the first leg
        (ox - w, oy + w, ox + 3 - w, oy + w),      # north of the first leg
        (ox + 3 + w, oy - w, ox + 3 + w, oy + 3 - w),  # east of the second leg
        (ox + 3 - w, oy + w, ox + 3 - w, oy + 3 + w),  # west of the second leg
        (ox + 3 - w, oy + 3 + w, ox + 6 + w, oy + 3 + w),  # north of the last leg
        (ox + 3 + w, oy + 3 - w, ox + 6 + w, oy + 3 - w),  # south of the last leg
        (ox + 6 + w, oy + 3 - w, ox + 6 + w, oy + 3 + w),  # past B
    ]
    return tuple(BorderLine(*segment) for segment in segments)


def track_b_scene() -> SceneSpec:
    """Thesis track B: from A to B along a winding corridor bordered by white lines; a touch restarts the run."""
    half_x, half_y = 4.5, 3.0
    track = TrackSpec(a_x_m=-3.0, a_y_m=-1.5, b_x_m=3.0, b_y_m=1.5, round_trip=False, lines=track_b_lines())
    marks = [*(_line_mark(line) for line in track.lines), *_point_marks(track)]
    return SceneSpec(name="course-B", floor_half_x_m=half_x, floor_half_y_m=half_y,
                     floor_rgba=(0.35, 0.37, 0.36, 1.0), boxes=tuple(room_walls(half_x, half_y)), marks=tuple(marks),
                     spawn=Pose2D(track.a_x_m, track.a_y_m, 0.0), track=track,
                     room_cameras=(corner_camera(-half_x + 0.2, -half_y + 0.2, 2.6),))


register_scene("lab", lab_scene)
register_scene("empty", empty_scene)
# The track scenes keep the names people configure (`--scene course-A`, the experiment's trials) from before
# "track" became the word for a driving track.
register_scene("course-A", track_a_scene)
register_scene("course-B", track_b_scene)


FLOOR_MARGIN_M = 0.5  # the floor reaches this far past the room's walls


def floor_patches(spec: SceneSpec) -> list[FloorPatch]:
    """The floor, then every mark painted on it in order, as the world builds them and the scene description
    reports them (one list for both, so a view drawn from the description cannot drift from the world)."""
    patches = [FloorPatch(0.0, 0.0, spec.floor_half_x_m + FLOOR_MARGIN_M, spec.floor_half_y_m + FLOOR_MARGIN_M, 0.0,
                          spec.floor_rgba, "floor")]
    for index, mark in enumerate(spec.marks):
        # Each painted layer sits a hair above the previous one so overlapping marks do not z-fight.
        patches.append(FloorPatch(mark.center_x_m, mark.center_y_m, mark.half_x_m, mark.half_y_m,
                                  MARK_THICKNESS_M + index * 1e-5, mark.rgba, mark.kind))
    return patches


def build_scene(client: Any, spec: SceneSpec, obstacle_collision_group: int) -> list[int]:
    """Creates the scene's bodies in a pybullet client (only from the world's thread); returns their ids."""
    bodies: list[int] = []
    floor, *marks = floor_patches(spec)
    floor_half = [floor.half_x_m, floor.half_y_m, FLOOR_THICKNESS_M / 2.0]
    floor_collision = client.createCollisionShape(client.GEOM_BOX, halfExtents=floor_half)
    floor_visual = _flat_visual(client, floor.half_x_m, floor.half_y_m, floor.rgba, FLOOR_THICKNESS_M / 2.0)
    bodies.append(client.createMultiBody(0, floor_collision, floor_visual, [0.0, 0.0, -FLOOR_THICKNESS_M / 2.0]))
    for box in spec.boxes:
        half = [box.half_x_m, box.half_y_m, box.height_m / 2.0]
        bodies.append(
            _static_box(client, half, (box.center_x_m, box.center_y_m, box.height_m / 2.0), box.yaw_rad, box.rgba)
        )
    for cylinder in spec.cylinders:
        collision = client.createCollisionShape(
            client.GEOM_CYLINDER, radius=cylinder.radius_m, height=cylinder.height_m
        )
        visual = client.createVisualShape(
            client.GEOM_CYLINDER, radius=cylinder.radius_m, length=cylinder.height_m, rgbaColor=cylinder.rgba
        )
        bodies.append(
            client.createMultiBody(
                0, collision, visual, [cylinder.center_x_m, cylinder.center_y_m, cylinder.height_m / 2.0]
            )
        )
    for body in bodies:
        client.setCollisionFilterGroupMask(body, -1, obstacle_collision_group, -1)
    for mark in marks:
        visual = _flat_visual(client, mark.half_x_m, mark.half_y_m, mark.rgba)
        bodies.append(client.createMultiBody(0, -1, visual, [mark.center_x_m, mark.center_y_m, mark.top_z_m]))
    return bodies


# The camera's renderer (pybullet's TinyRenderer, on the CPU) scans every triangle's screen bounding box: a box's
# hidden bottom and edge faces under the floor and the paint cost as much as the visible top. A flat patch
# is its top face alone, cut into tiles no longer than this so a long line seen in perspective has small boxes.
FLAT_TILE_M = 1.0


def _flat_visual(client: Any, half_x_m: float, half_y_m: float, rgba: Rgba, z_m: float = 0.0) -> int:
    """A visual shape of an upward-facing rectangle z_m above its body's origin (floors and paint), in tiles."""
    nx = max(1, math.ceil(2 * half_x_m / FLAT_TILE_M))
    ny = max(1, math.ceil(2 * half_y_m / FLAT_TILE_M))
    xs = [-half_x_m + 2 * half_x_m * i / nx for i in range(nx + 1)]
    ys = [-half_y_m + 2 * half_y_m * j / ny for j in range(ny + 1)]
    vertices = [[x, y, 0.0] for y in ys for x in xs]
    indices = []
    for j in range(ny):
        for i in range(nx):
            a = j * (nx + 1) + i
            b, c, d = a + 1, a + nx + 1, a + nx + 2
            indices += [a, b, d, a, d, c]
    return client.createVisualShape(client.GEOM_MESH, vertices=vertices, indices=indices,
                                    normals=[[0.0, 0.0, 1.0]] * len(vertices), rgbaColor=rgba,
                                    visualFramePosition=[0.0, 0.0, z_m])


def _static_box(
    client: Any, half_extents: list[float], position: tuple[float, float, float], yaw_rad: float, rgba: Rgba
) -> int:
    collision = client.createCollisionShape(client.GEOM_BOX, halfExtents=half_extents)
    visual = client.createVisualShape(client.GEOM_BOX, halfExtents=half_extents, rgbaColor=rgba)
    orientation = client.getQuaternionFromEuler([0.0, 0.0, yaw_rad])
    return client.createMultiBody(0, collision, visual, list(position), orientation)
