"""The usage figures, computed from the stored history for a scope and a window: the sessions (the recordings
index), time on robots per student, a week-by-hour heat map of use, queue waits and their distribution, and each
robot's uptime and faults. Pure reads of the session handed in; every time is UTC, days and hours are the viewer's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timedelta

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.analytics.schemas import Window
from middleware.analytics.scope import Scope
from middleware.models import Robot, User
from middleware.models.accounts import as_utc
from middleware.models.analytics import QueueWait, RobotOutage
from middleware.models.recordings import Recording
from middleware.models.robots import RobotMaintenance

# Queue waits are counted in these bins [low, high) of seconds: no wait, under half a minute, ..., half an hour on.
WAIT_BINS_S = (0.0, 1.0, 30.0, 60.0, 120.0, 300.0, 600.0, 1800.0, math.inf)
PRACTICE_PREFIX = "practice-"


@dataclass(frozen=True)
class SessionRow:
    """One controlled session as the sessions table shows it."""

    id: int
    user_id: int
    username: str
    robot_name: str
    kind: str
    started_at: datetime
    ended_at: datetime | None
    end_reason: str | None
    command_count: int
    skill_count: int
    plan_count: int

    def seconds_within(self, start: datetime, end: datetime) -> float:
        """How long the session ran within [start, end) (an open one runs until end)."""
        stop = min(self.ended_at or end, end)
        return max(0.0, (stop - max(self.started_at, start)).total_seconds())

    def to_dict(self, now: datetime) -> dict[str, object]:
        """The row as JSON (duration so far for an open one)."""
        return {"id": self.id, "user_id": self.user_id, "username": self.username, "robot_name": self.robot_name,
                "kind": self.kind, "started_at": self.started_at.isoformat(),
                "ended_at": self.ended_at.isoformat() if self.ended_at else None,
                "duration_s": round(((self.ended_at or now) - self.started_at).total_seconds(), 1),
                "command_count": self.command_count, "skill_count": self.skill_count,
                "plan_count": self.plan_count, "end_reason": self.end_reason or ("ongoing" if not self.ended_at
                                                                                  else None)}


def sessions(session: Session, scope: Scope, window: Window, limit: int | None = None) -> list[SessionRow]:
    """The sessions of the scope's people that overlap the window, newest first."""
    query = (select(Recording, User.username).join(User, User.id == Recording.user_id)
             .where(Recording.started_at < window.end,
                    (Recording.ended_at.is_(None)) | (Recording.ended_at > window.start))
             .order_by(Recording.started_at.desc(), Recording.id.desc()))
    if scope.student_ids is not None:
        query = query.where(Recording.user_id.in_(sorted(scope.student_ids)))
    if limit is not None:
        query = query.limit(limit)
    return [SessionRow(r.id, r.user_id, name, r.robot_name, r.kind, as_utc(r.started_at),
                       as_utc(r.ended_at) if r.ended_at else None, r.end_reason, r.command_count, r.skill_count,
                       r.plan_count) for r, name in session.execute(query)]


def time_per_student(session: Session, scope: Scope, window: Window, rows: list[SessionRow],
                     now: datetime) -> list[dict[str, object]]:
    """Per person: sessions and seconds on robots within the window (a course's students all listed, at 0 too),
    most time first."""
    end = min(window.end, now)
    totals: dict[int, list[float]] = {}
    for row in rows:
        entry = totals.setdefault(row.user_id, [0, 0.0])
        entry[0] += 1
        entry[1] += row.seconds_within(window.start, end)
    ids = set(totals) | set(scope.student_ids or ())
    found = session.execute(select(User.id, User.username).where(User.id.in_(sorted(ids))))
    names = {int(i): str(n) for i, n in found}
    result = [{"user_id": uid, "username": names.get(uid, str(uid)), "sessions": int(totals.get(uid, [0, 0.0])[0]),
               "seconds": round(totals.get(uid, [0, 0.0])[1], 1)} for uid in ids]
    return sorted(result, key=lambda r: (-float(r["seconds"]), str(r["username"])))  # type: ignore[arg-type]


def heat_map(rows: list[SessionRow], window: Window, now: datetime) -> list[list[float]]:
    """Minutes of robot use per weekday (0 Monday .. 6 Sunday) and hour (0-23) of the viewer's zone."""
    grid = [[0.0] * 24 for _ in range(7)]
    end = min(window.end, now)
    for row in rows:
        start = max(row.started_at, window.start)
        stop = min(row.ended_at or end, end)
        while start < stop:
            local = start + window.offset
            hour_end = local.replace(minute=0, second=0, microsecond=0) + timedelta(hours=1) - window.offset
            piece_end = min(hour_end, stop)
            grid[local.weekday()][local.hour] += (piece_end - start).total_seconds() / 60.0
            start = piece_end
    return [[round(v, 2) for v in day] for day in grid]


def queue_waits(session: Session, scope: Scope, window: Window) -> list[tuple[QueueWait, str]]:
    """The turns granted in the window to the scope's people, with how long each was waited for, oldest first."""
    query = (select(QueueWait, User.username).join(User, User.id == QueueWait.user_id)
             .where(QueueWait.granted_at >= window.start, QueueWait.granted_at < window.end)
             .order_by(QueueWait.granted_at, QueueWait.id))
    if scope.student_ids is not None:
        query = query.where(QueueWait.user_id.in_(sorted(scope.student_ids)))
    return [(wait, name) for wait, name in session.execute(query)]


def _nearest_rank(ordered: list[float], fraction: float) -> float:
    return ordered[max(0, math.ceil(fraction * len(ordered)) - 1)]


def wait_summary(waits: list[float]) -> dict[str, object]:
    """Count, mean, median, 90th percentile (nearest rank) and longest wait in seconds, and the count per bin."""
    ordered = sorted(waits)
    bins = [{"low_s": low, "high_s": None if math.isinf(high) else high,
             "count": sum(1 for w in ordered if low <= w < high)}
            for low, high in zip(WAIT_BINS_S, WAIT_BINS_S[1:], strict=False)]
    if not ordered:
        return {"count": 0, "mean_s": None, "median_s": None, "p90_s": None, "max_s": None, "bins": bins}
    middle = len(ordered) // 2
    median = ordered[middle] if len(ordered) % 2 else (ordered[middle - 1] + ordered[middle]) / 2
    return {"count": len(ordered), "mean_s": round(sum(ordered) / len(ordered), 1), "median_s": round(median, 1),
            "p90_s": round(_nearest_rank(ordered, 0.9), 1), "max_s": round(ordered[-1], 1), "bins": bins}


def robots(session: Session, window: Window, rows: list[SessionRow], now: datetime) -> list[dict[str, object]]:
    """Per lab robot: the scope's sessions and hours on it, its outages (times it did not answer, as the access rule
    saw them), the downtime and uptime within the window so far, and the maintenance actions taken on it."""
    end = min(window.end, now)
    span_s = (end - window.start).total_seconds()
    names = set(session.scalars(select(Robot.name)))
    names |= {r.robot_name for r in rows if not r.robot_name.startswith(PRACTICE_PREFIX)}
    outages = session.scalars(select(RobotOutage).where(
        RobotOutage.started_at < end, (RobotOutage.ended_at.is_(None)) | (RobotOutage.ended_at > window.start)))
    down: dict[str, list[float]] = {}
    for outage in outages:
        stop = min(as_utc(outage.ended_at) if outage.ended_at else end, end)
        seconds = max(0.0, (stop - max(as_utc(outage.started_at), window.start)).total_seconds())
        entry = down.setdefault(outage.robot_name, [0, 0.0])
        entry[0] += 1
        entry[1] += seconds
        names.add(outage.robot_name)
    actions: dict[str, dict[str, int]] = {}
    for name, action in session.execute(select(RobotMaintenance.robot_name, RobotMaintenance.action).where(
            RobotMaintenance.created_at >= window.start, RobotMaintenance.created_at < window.end)):
        per = actions.setdefault(name, {})
        per[action] = per.get(action, 0) + 1
        names.add(name)
    result = []
    for name in sorted(n for n in names if not n.startswith(PRACTICE_PREFIX)):
        mine = [r for r in rows if r.robot_name == name]
        outage_count, down_s = down.get(name, [0, 0.0])
        result.append({
            "robot_name": name, "sessions": len(mine),
            "seconds_used": round(sum(r.seconds_within(window.start, end) for r in mine), 1),
            "outages": int(outage_count), "downtime_s": round(down_s, 1),
            "uptime_pct": round(100.0 * (1.0 - down_s / span_s), 2) if span_s > 0 else None,
            "maintenance": actions.get(name, {}),
        })
    return result
