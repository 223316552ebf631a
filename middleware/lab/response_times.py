"""A console's response-time figures (the 2003 paper's table 1, as its panel shows them): checked at the edge and
kept per user and robot, so a tutor reads every student's from any worker."""

from __future__ import annotations

import math
from datetime import UTC, datetime
from typing import Any

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware.errors import ApiError
from middleware.models.lab import ResponseTimeReport

KINDS = ("skill", "drive")
LEGS = ("total", "client", "robot")
FIGURES = ("min", "mean", "max", "jitter")
DELIVERY = ("sent", "late", "lost")
MAX_MS = 3_600_000.0  # an hour: a longer round trip is no measurement
MAX_COUNT = 10**9


def _invalid(field: str, message: str) -> ApiError:
    return ApiError(400, "invalid_field", message, field)


def _milliseconds(value: object, field: str) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) \
            or not 0 <= value <= MAX_MS:
        raise _invalid(field, f"{field} must be a number of milliseconds from 0 to {MAX_MS:.0f}, or null.")
    return float(value)  # unrounded, so the tutor's page rounds it as the student's panel did


def _count(value: object, field: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= MAX_COUNT:
        raise _invalid(field, f"{field} must be a whole number from 0 to {MAX_COUNT}.")
    return value


def _object(value: object, field: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise _invalid(field, f"{field} must be an object.")
    return value


def parse_report(body: object) -> dict[str, Any]:
    """{skill|drive: {count, total|client|robot: {min, mean, max, jitter}}, delivery: {sent, late, lost},
    throughput_bps}, each number checked (an error names the field, e.g. skill.robot.max)."""
    report = _object(body, "body")
    figures: dict[str, Any] = {}
    for kind in KINDS:
        timed = _object(report.get(kind), kind)
        figures[kind] = {"count": _count(timed.get("count"), f"{kind}.count")}
        for leg in LEGS:
            leg_figures = _object(timed.get(leg), f"{kind}.{leg}")
            figures[kind][leg] = {name: _milliseconds(leg_figures.get(name), f"{kind}.{leg}.{name}")
                                  for name in FIGURES}
    delivery = _object(report.get("delivery"), "delivery")
    figures["delivery"] = {name: _count(delivery.get(name), f"delivery.{name}") for name in DELIVERY}
    throughput = report.get("throughput_bps")
    if isinstance(throughput, bool) or not isinstance(throughput, int | float) or not math.isfinite(throughput) \
            or not 0 <= throughput <= 1e12:
        raise _invalid("throughput_bps", "throughput_bps must be a number of bytes per second, 0 or more.")
    figures["throughput_bps"] = round(float(throughput), 1)
    return figures


def record_report(session: Session, user_id: int, robot_name: str, figures: dict[str, Any]) -> None:
    """Keeps figures as user_id's latest for robot_name (flushed; the request's end commits)."""
    def stored() -> ResponseTimeReport | None:
        return session.scalar(select(ResponseTimeReport).where(ResponseTimeReport.user_id == user_id,
                                                               ResponseTimeReport.robot_name == robot_name))

    report = stored()
    if report is None:
        try:
            with session.begin_nested():  # the user's other tab may insert the same row first
                session.add(ResponseTimeReport(user_id=user_id, robot_name=robot_name, figures=figures))
            return
        except IntegrityError:
            report = stored()
    if report is not None:
        report.figures = figures
        report.updated_at = datetime.now(UTC)
        session.flush()
