"""A* over the obstacle grid, with obstacles grown by the robot's size so a path keeps the body clear."""

from __future__ import annotations

import heapq
import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from skill_server.skills.obstacles import ObstacleMap

WINDOW_MARGIN_M = 2.5  # the search covers the robot, the goal and this much around them
CAUTION_COST = 4.0  # extra cost per cell near obstacles, so paths keep to the middle of passages
MARGIN_COST = 25.0
PLAN_MARGIN_M = 0.02  # paths keep the body this much off the centres of seen obstacle cells
ROOM_AROUND_M = 0.15  # around the robot (and a goal it can stand on) the grown zone is opened, so it can leave
SUGGESTION_ROOM_M = 0.10  # a suggested point has seen-free floor this much beyond the body all round
ENCLOSED_WITHIN_M = 1.0  # a goal walled in by echoes within this distance lies inside an obstacle


@dataclass(frozen=True)
class PlanResult:
    """A path in world coordinates, or why there is none."""

    waypoints: tuple[tuple[float, float], ...]
    goal_blocked: bool  # the goal lies inside a seen obstacle: a body standing there would overlap an echo
    found: bool
    obstacle_xy: tuple[float, float] | None = None  # when goal_blocked: the seen obstacle cell nearest the goal


@dataclass(frozen=True)
class _Window:
    """The part of the grid a plan looks at, with obstacles grown by the body, in window cells."""

    x0: int
    y0: int
    occupied: np.ndarray
    blocked: np.ndarray  # the body's centre may not enter
    start: tuple[int, int]
    goal: tuple[int, int]


def dilate(mask: np.ndarray, radius_cells: float) -> np.ndarray:
    """Grows True cells to every cell whose centre lies within radius_cells of theirs (numpy shifts, no scipy)."""
    if radius_cells < 1.0:
        return mask.copy()
    grown = mask.copy()
    nx, ny = mask.shape
    reach = int(math.floor(radius_cells))
    for dx in range(-reach, reach + 1):
        for dy in range(-reach, reach + 1):
            if (dx or dy) and dx * dx + dy * dy <= radius_cells * radius_cells:
                grown[max(dx, 0):nx + min(dx, 0), max(dy, 0):ny + min(dy, 0)] |= mask[
                    max(-dx, 0):nx + min(-dx, 0), max(-dy, 0):ny + min(-dy, 0)
                ]
    return grown


def _window(grid: ObstacleMap, start_xy: tuple[float, float], goal_xy: tuple[float, float],
            body_radius_m: float, open_goal: bool = True) -> _Window | None:
    """The search window around start and goal, or None when either lies off the grid."""
    res = grid.resolution_m
    (sx, sy), (gx, gy) = grid.cell_of(*start_xy), grid.cell_of(*goal_xy)
    pad = int(WINDOW_MARGIN_M / res)
    x0, x1 = max(0, min(sx, gx) - pad), min(grid.size, max(sx, gx) + pad + 1)
    y0, y1 = max(0, min(sy, gy) - pad), min(grid.size, max(sy, gy) + pad + 1)
    if not (x0 <= gx < x1 and y0 <= gy < y1 and x0 <= sx < x1 and y0 <= sy < y1):
        return None
    occupied = grid.occupied_window(x0, x1, y0, y1)
    blocked = dilate(occupied, (body_radius_m + PLAN_MARGIN_M) / res)
    window = _Window(x0, y0, occupied, blocked, (sx - x0, sy - y0), (gx - x0, gy - y0))
    # The robot may already stand in the grown zone (it brushed past a wall); let it leave.
    _open_around(window, window.start, res, keep_occupied=False)
    if open_goal and blocked[window.goal]:
        # A goal the robot has stood on is reachable whatever the grid says now (its frame may have drifted since);
        # a goal just inside the grown zone but clear of every echo by the body's size may be approached.
        _open_around(window, window.goal, res, keep_occupied=not grid.was_visited(*goal_xy))
    return window


def _open_around(window: _Window, cell: tuple[int, int], res: float, keep_occupied: bool) -> None:
    r = int(math.ceil(ROOM_AROUND_M / res))
    area = (slice(max(0, cell[0] - r), cell[0] + r + 1), slice(max(0, cell[1] - r), cell[1] + r + 1))
    window.blocked[area] = window.occupied[area] if keep_occupied else False


def _nearest_obstacle(grid: ObstacleMap, window: _Window, goal_xy: tuple[float, float],
                      within_m: float) -> tuple[float, tuple[float, float]] | None:
    """Distance from the goal to the centre of the nearest occupied cell within within_m, and that centre."""
    reach = int(math.ceil(within_m / grid.resolution_m)) + 1
    gx, gy = window.goal
    lx, ly = max(0, gx - reach), max(0, gy - reach)
    xs, ys = np.nonzero(window.occupied[lx:gx + reach + 1, ly:gy + reach + 1])
    if xs.size == 0:
        return None
    centres_x = grid.origin_m + (xs + lx + window.x0 + 0.5) * grid.resolution_m
    centres_y = grid.origin_m + (ys + ly + window.y0 + 0.5) * grid.resolution_m
    distances = np.hypot(centres_x - goal_xy[0], centres_y - goal_xy[1])
    best = int(np.argmin(distances))
    if distances[best] > within_m:
        return None
    return float(distances[best]), (float(centres_x[best]), float(centres_y[best]))


def plan_path(
    grid: ObstacleMap,
    start_xy: tuple[float, float],
    goal_xy: tuple[float, float],
    body_radius_m: float,
    margin_m: float = 0.10,
    caution_m: float = 0.25,
) -> PlanResult:
    """Cheapest 8-connected path from start to goal keeping the body off obstacles (none if blocked).

    The goal counts as inside an obstacle only when an echo's cell lies so close that a body there would overlap
    the echo wherever in its cell it fell (never for a point the robot has stood on): a point whose clearance is
    the body's radius plus a few centimetres is planned to, not refused.
    """
    res = grid.resolution_m
    window = _window(grid, start_xy, goal_xy, body_radius_m)
    if window is None:
        return PlanResult((), False, False)
    certain_overlap_m = body_radius_m - res / math.sqrt(2.0)
    nearest = _nearest_obstacle(grid, window, goal_xy, body_radius_m)
    if nearest is not None and nearest[0] < certain_overlap_m and not grid.was_visited(*goal_xy):
        return PlanResult((), True, False, nearest[1])
    near = dilate(window.occupied, (body_radius_m + margin_m) / res)
    caution = dilate(window.occupied, (body_radius_m + margin_m + caution_m) / res)
    extra = np.where(near, MARGIN_COST, np.where(caution, CAUTION_COST, 0.0))
    cells = _astar(window.blocked, extra, window.start, window.goal)
    if cells is None:
        # Walled in by echoes with no gap the body fits through, the goal lies inside an obstacle whose inside the
        # laser cannot see (a crate's middle).
        enclosed = _enclosed(window.blocked, window.goal, int(ENCLOSED_WITHIN_M / res))
        nearest = _nearest_obstacle(grid, window, goal_xy, ENCLOSED_WITHIN_M) if enclosed else None
        return PlanResult((), nearest is not None, False, nearest[1] if nearest else None)
    waypoints = tuple(grid.center_of(cx + window.x0, cy + window.y0) for cx, cy in _thin(cells))
    return PlanResult(waypoints[1:] + (goal_xy,) if len(waypoints) > 1 else (goal_xy,), False, True)


def _enclosed(blocked: np.ndarray, cell: tuple[int, int], reach_cells: int) -> bool:
    """Whether the places the body could stand that join cell all lie within reach_cells of it (walled in)."""
    free = (~blocked).tolist()
    nx, ny = blocked.shape
    seen = {cell}
    queue = deque([cell])
    while queue:
        x, y = queue.popleft()
        for dx, dy, _ in _STEPS:
            nxt_x, nxt_y = x + dx, y + dy
            if not (0 <= nxt_x < nx and 0 <= nxt_y < ny):
                return False  # the window's edge: open country
            if (nxt_x, nxt_y) in seen or not free[nxt_x][nxt_y]:
                continue
            if max(abs(nxt_x - cell[0]), abs(nxt_y - cell[1])) > reach_cells:
                return False
            seen.add((nxt_x, nxt_y))
            queue.append((nxt_x, nxt_y))
    return True


def nearest_reachable_point(grid: ObstacleMap, start_xy: tuple[float, float], goal_xy: tuple[float, float],
                            body_radius_m: float) -> tuple[float, float] | None:
    """The point nearest the goal that a path from the start reaches and where the body has room, or None.

    Room means floor seen free by the laser (or stood on) all round the body and a little more, so the point is
    one the robot can in fact reach; when there is none, the reachable cell nearest the goal is offered.
    """
    window = _window(grid, start_xy, goal_xy, body_radius_m, open_goal=False)
    if window is None:
        return None
    res = grid.resolution_m
    reachable = _flood(window.blocked, window.start)
    x1, y1 = window.x0 + reachable.shape[0], window.y0 + reachable.shape[1]
    known = grid.seen_free[window.x0:x1, window.y0:y1] | grid.visited[window.x0:x1, window.y0:y1]
    roomy = reachable & ~dilate(~known | window.occupied, (body_radius_m + SUGGESTION_ROOM_M) / res)
    xs, ys = np.nonzero(roomy if roomy.any() else reachable)
    goal_x = (goal_xy[0] - grid.origin_m) / res - 0.5 - window.x0  # the goal in window cells
    goal_y = (goal_xy[1] - grid.origin_m) / res - 0.5 - window.y0
    best = int(np.argmin((xs - goal_x) ** 2 + (ys - goal_y) ** 2))
    return grid.center_of(int(xs[best]) + window.x0, int(ys[best]) + window.y0)


def _flood(blocked: np.ndarray, start: tuple[int, int]) -> np.ndarray:
    """The cells an 8-connected walk from start reaches without entering a blocked one."""
    free = (~blocked).tolist()
    nx, ny = blocked.shape
    reached = np.zeros(blocked.shape, dtype=bool)
    reached[start] = True
    queue = deque([start])
    while queue:
        x, y = queue.popleft()
        for dx, dy, _ in _STEPS:
            nxt_x, nxt_y = x + dx, y + dy
            if 0 <= nxt_x < nx and 0 <= nxt_y < ny and free[nxt_x][nxt_y] and not reached[nxt_x, nxt_y]:
                reached[nxt_x, nxt_y] = True
                queue.append((nxt_x, nxt_y))
    return reached


_STEPS = [(1, 0, 1.0), (-1, 0, 1.0), (0, 1, 1.0), (0, -1, 1.0),
          (1, 1, math.sqrt(2)), (1, -1, math.sqrt(2)), (-1, 1, math.sqrt(2)), (-1, -1, math.sqrt(2))]


def _astar(
    blocked: np.ndarray, extra: np.ndarray, start: tuple[int, int], goal: tuple[int, int]
) -> list[tuple[int, int]] | None:
    nx, ny = blocked.shape
    blocked_list = blocked.tolist()  # list lookups are several times faster than numpy scalars here
    extra_list = extra.tolist()
    gx, gy = goal

    def heuristic(x: int, y: int) -> float:
        dx, dy = abs(x - gx), abs(y - gy)
        return (dx + dy) + (math.sqrt(2) - 2) * min(dx, dy)

    best = {start: 0.0}
    parent: dict[tuple[int, int], tuple[int, int]] = {}
    frontier = [(heuristic(*start), 0.0, start)]
    closed: set[tuple[int, int]] = set()
    while frontier:
        _, cost, cell = heapq.heappop(frontier)
        if cell == goal:
            path = [cell]
            while cell in parent:
                cell = parent[cell]
                path.append(cell)
            return path[::-1]
        if cell in closed:
            continue
        closed.add(cell)
        x, y = cell
        for dx, dy, step in _STEPS:
            nxt_x, nxt_y = x + dx, y + dy
            if not (0 <= nxt_x < nx and 0 <= nxt_y < ny) or blocked_list[nxt_x][nxt_y]:
                continue
            new_cost = cost + step * (1.0 + extra_list[nxt_x][nxt_y])
            nxt = (nxt_x, nxt_y)
            if new_cost < best.get(nxt, math.inf):
                best[nxt] = new_cost
                parent[nxt] = cell
                heapq.heappush(frontier, (new_cost + heuristic(nxt_x, nxt_y), new_cost, nxt))
    return None


def _thin(cells: list[tuple[int, int]], every: int = 4) -> list[tuple[int, int]]:
    """Keeps every few cells and the turns, enough for a look-ahead follower."""
    kept = [cells[0]]
    for index in range(1, len(cells) - 1):
        if index % every == 0:
            kept.append(cells[index])
    kept.append(cells[-1])
    return kept


def path_is_blocked(grid: ObstacleMap, waypoints: tuple[tuple[float, float], ...], body_radius_m: float,
                    start_xy: tuple[float, float], check_length_m: float = 1.5) -> bool:
    """True if the next stretch of the path passes closer to a seen obstacle than the body's radius."""
    res = grid.resolution_m
    points = [start_xy]
    travelled = 0.0
    for point in waypoints:
        points.append(point)
        travelled += math.dist(points[-2], point)
        if travelled > check_length_m:
            break
    # Sample the stretch every cell, then compare every sample with the occupied cells around it at once.
    samples = [np.linspace(a, b, max(1, int(math.dist(a, b) / res)) + 1)[1:]
               for a, b in zip(points[:-1], points[1:], strict=True)]
    if not samples:
        return False
    points_m = np.concatenate(samples)
    # Where the planner opened the grown zone (round the robot and the goal), the path may pass near echoes.
    opened = np.hypot(*(points_m - np.asarray(start_xy)).T) < ROOM_AROUND_M
    opened |= np.hypot(*(points_m - np.asarray(waypoints[-1])).T) < ROOM_AROUND_M
    if opened.all():
        return False
    cells = np.floor((points_m[~opened] - grid.origin_m) / res).astype(np.int64)
    radius_cells = int(math.ceil(body_radius_m / res))
    lo = np.maximum(cells.min(axis=0) - radius_cells, 0)
    hi = np.minimum(cells.max(axis=0) + radius_cells + 1, grid.size)
    if np.any(hi <= lo):
        return False
    occupied_x, occupied_y = np.nonzero(grid.occupied_window(lo[0], hi[0], lo[1], hi[1]))
    if occupied_x.size == 0:
        return False
    dx = cells[:, 0:1] - (occupied_x[None, :] + lo[0])
    dy = cells[:, 1:2] - (occupied_y[None, :] + lo[1])
    return bool(np.any(dx * dx + dy * dy <= radius_cells * radius_cells))
