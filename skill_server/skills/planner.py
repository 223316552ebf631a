"""A* over the obstacle grid, with obstacles grown by the robot's size so a path keeps the body clear."""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from skill_server.skills.obstacles import ObstacleMap

WINDOW_MARGIN_M = 2.5  # the search covers the robot, the goal and this much around them
CAUTION_COST = 4.0  # extra cost per cell near obstacles, so paths keep to the middle of passages
MARGIN_COST = 25.0


@dataclass(frozen=True)
class PlanResult:
    """A path in world coordinates, or why there is none."""

    waypoints: tuple[tuple[float, float], ...]
    goal_blocked: bool  # the goal itself lies inside an obstacle grown by the robot's radius
    found: bool


def dilate(mask: np.ndarray, radius_cells: int) -> np.ndarray:
    """Grows True cells by a disk of radius_cells (numpy shifts, no scipy)."""
    if radius_cells <= 0:
        return mask.copy()
    grown = mask.copy()
    nx, ny = mask.shape
    for dx in range(-radius_cells, radius_cells + 1):
        for dy in range(-radius_cells, radius_cells + 1):
            if (dx or dy) and dx * dx + dy * dy <= radius_cells * radius_cells:
                grown[max(dx, 0):nx + min(dx, 0), max(dy, 0):ny + min(dy, 0)] |= mask[
                    max(-dx, 0):nx + min(-dx, 0), max(-dy, 0):ny + min(-dy, 0)
                ]
    return grown


def plan_path(
    grid: ObstacleMap,
    start_xy: tuple[float, float],
    goal_xy: tuple[float, float],
    body_radius_m: float,
    margin_m: float = 0.10,
    caution_m: float = 0.25,
) -> PlanResult:
    """Cheapest 8-connected path from start to goal keeping the body off obstacles (none if blocked)."""
    res = grid.resolution_m
    (sx, sy), (gx, gy) = grid.cell_of(*start_xy), grid.cell_of(*goal_xy)
    pad = int(WINDOW_MARGIN_M / res)
    x0, x1 = max(0, min(sx, gx) - pad), min(grid.size, max(sx, gx) + pad + 1)
    y0, y1 = max(0, min(sy, gy) - pad), min(grid.size, max(sy, gy) + pad + 1)
    if not (x0 <= gx < x1 and y0 <= gy < y1 and x0 <= sx < x1 and y0 <= sy < y1):
        return PlanResult((), False, False)
    occupied = grid.occupied()[x0:x1, y0:y1]
    blocked = dilate(occupied, int(math.ceil((body_radius_m + 0.02) / res)))
    near = dilate(occupied, int(math.ceil((body_radius_m + margin_m) / res)))
    caution = dilate(occupied, int(math.ceil((body_radius_m + margin_m + caution_m) / res)))
    lsx, lsy, lgx, lgy = sx - x0, sy - y0, gx - x0, gy - y0
    if blocked[lgx, lgy]:
        return PlanResult((), True, False)
    # The robot may already stand in the grown zone (it brushed past a wall); let it leave.
    r = int(math.ceil(0.15 / res))
    blocked[max(0, lsx - r):lsx + r + 1, max(0, lsy - r):lsy + r + 1] = False
    extra = np.where(near, MARGIN_COST, np.where(caution, CAUTION_COST, 0.0))
    cells = _astar(blocked, extra, (lsx, lsy), (lgx, lgy))
    if cells is None:
        return PlanResult((), False, False)
    waypoints = tuple(grid.center_of(cx + x0, cy + y0) for cx, cy in _thin(cells))
    return PlanResult(waypoints[1:] + (goal_xy,) if len(waypoints) > 1 else (goal_xy,), False, True)


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
    cells = np.floor((np.concatenate(samples) - grid.origin_m) / res).astype(np.int64)
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
