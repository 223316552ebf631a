"""The recordings' settings: where the files go (a directory every worker and host shares, like the lesson videos),
the disk limits and how long a recording is kept. Read from app.config, else from the TELELAB_ environment."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from flask import Flask

from middleware.config import ConfigError

MB = 1024 * 1024


@dataclass(frozen=True)
class RecordingSettings:
    """What create_app configured for the recorder."""

    enabled: bool
    directory: Path
    max_total_bytes: int
    max_user_bytes: int
    retention_days: int


def _number(app: Flask, key: str, env: str, default: str, low: int, high: int) -> int:
    raw = str(app.config.get(key, os.environ.get(env, default))).strip()
    if not raw.isascii() or not raw.isdigit() or not low <= int(raw) <= high:
        raise ConfigError(f"{env} must be a whole number from {low} to {high}, not {raw!r}.")
    return int(raw)


def load(app: Flask) -> RecordingSettings:
    """The app's recording settings (a wrong value stops the start with a sentence naming the setting)."""
    enabled = str(app.config.get("RECORDINGS_ENABLED", os.environ.get("TELELAB_RECORDINGS", "1"))).lower()
    directory = app.config.get("RECORDINGS_DIR") or os.environ.get("TELELAB_RECORDINGS_DIR") or str(
        Path(app.instance_path) / "recordings")
    return RecordingSettings(
        enabled=enabled in {"1", "true", "yes", "on"},
        directory=Path(str(directory)),
        max_total_bytes=_number(app, "RECORDINGS_MAX_TOTAL_MB", "TELELAB_RECORDINGS_MAX_TOTAL_MB", "20000", 1,
                                10_000_000) * MB,
        max_user_bytes=_number(app, "RECORDINGS_MAX_USER_MB", "TELELAB_RECORDINGS_MAX_USER_MB", "500", 1,
                               10_000_000) * MB,
        retention_days=_number(app, "RECORDINGS_RETENTION_DAYS", "TELELAB_RECORDINGS_RETENTION_DAYS", "365", 1,
                               36_500),
    )
