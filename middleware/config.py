"""Configuration read from the environment (TELELAB_*), with defaults for a single machine."""

from __future__ import annotations

import os
import secrets
from dataclasses import dataclass
from datetime import timedelta
from pathlib import Path


class ConfigError(ValueError):
    """A TELELAB_* setting that cannot be used; the message names it."""


@dataclass(frozen=True)
class RobotAddress:
    """A robot the middleware may reach: its name (URL-safe) and its skill server's gRPC address."""

    name: str
    address: str

    @property
    def title(self) -> str:
        """A human title derived from the name: 'lab-1' -> 'Lab 1', 'course-a' -> 'Course A'."""
        title = self.name.replace("-", " ").replace("_", " ").capitalize()
        return " ".join(word.upper() if len(word) == 1 else word for word in title.split(" "))


def parse_robots(value: str) -> tuple[RobotAddress, ...]:
    """Parses TELELAB_ROBOTS: 'name=host:port' entries separated by commas."""
    robots: list[RobotAddress] = []
    for entry in filter(None, (part.strip() for part in value.split(","))):
        name, sep, address = entry.partition("=")
        name, address = name.strip(), address.strip()
        if not sep or not name or ":" not in address:
            raise ConfigError(f"TELELAB_ROBOTS entry {entry!r} must look like 'lab-1=127.0.0.1:50051'.")
        if not all(c.isalnum() or c in "-_" for c in name) or len(name) > 32:
            raise ConfigError(f"TELELAB_ROBOTS name {name!r} may use only letters, digits, '-' and '_'.")
        if any(r.name == name for r in robots):
            raise ConfigError(f"TELELAB_ROBOTS names robot {name!r} twice.")
        robots.append(RobotAddress(name, address))
    return tuple(robots)


def persistent_secret_key(instance_dir: Path) -> str:
    """A secret key kept in the instance folder, so sessions survive a restart on one machine."""
    path = instance_dir / "secret_key"
    if path.exists():
        return path.read_text().strip()
    instance_dir.mkdir(parents=True, exist_ok=True)
    key = secrets.token_urlsafe(48)
    path.touch(mode=0o600)
    path.write_text(key)
    return key


def _positive_number(env: dict[str, str], name: str, default: str) -> float:
    """The number in env[name] (default when unset); a ConfigError naming it unless finite and above 0."""
    raw = env.get(name, default)
    try:
        value = float(raw)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        raise ConfigError(f"{name} must be a number above 0, not {raw!r}.")
    return value


def trusted_proxies(env: dict[str, str]) -> int:
    """TELELAB_TRUSTED_PROXIES: how many proxies in front of the app set X-Forwarded-* (0: trust none)."""
    raw = env.get("TELELAB_TRUSTED_PROXIES", "0").strip()
    if raw not in {"0", "1", "2", "3", "4", "5"}:
        raise ConfigError(f"TELELAB_TRUSTED_PROXIES must be a whole number from 0 to 5, not {raw!r}.")
    return int(raw)


def prediction_cap(env: dict[str, str]) -> int:
    """TELELAB_PREDICTION_CAP: how many plan predictions (fast robots, a core each) one web process runs at once."""
    raw = env.get("TELELAB_PREDICTION_CAP", "2").strip()
    if not raw.isascii() or not raw.isdigit() or int(raw) > 64:
        raise ConfigError(f"TELELAB_PREDICTION_CAP must be a whole number from 0 to 64, not {raw!r}.")
    return int(raw)


# PostgreSQL connections a web worker may hold: its pool (requests, sockets' work, background duties, the elections'
# advisory locks) and the event bus's LISTEN connection outside it (middleware/events.py).
LISTENER_CONNECTIONS = 1


def _whole_number(env: dict[str, str], name: str, default: str, low: int, high: int) -> int:
    raw = env.get(name, default).strip()
    if not raw.isascii() or not raw.isdigit() or not low <= int(raw) <= high:
        raise ConfigError(f"{name} must be a whole number from {low} to {high}, not {raw!r}.")
    return int(raw)


@dataclass(frozen=True)
class ConnectionBudget:
    """What a web tier may hold of PostgreSQL's connections: each worker's pool (TELELAB_DB_POOL_SIZE kept open,
    TELELAB_DB_MAX_OVERFLOW more under load) plus its LISTEN connection, times the workers of every web host."""

    pool_size: int
    max_overflow: int
    web_hosts: int

    @property
    def per_worker(self) -> int:
        return self.pool_size + self.max_overflow + LISTENER_CONNECTIONS

    def needed(self, workers: int) -> int:
        """The most the web tier holds with workers per host; a rolling restart runs one worker more for a moment."""
        return self.web_hosts * (workers + 1) * self.per_worker


def connection_budget(env: dict[str, str] | None = None) -> ConnectionBudget:
    """TELELAB_DB_POOL_SIZE, TELELAB_DB_MAX_OVERFLOW and TELELAB_WEB_HOSTS (how many web hosts share the database)."""
    env = dict(os.environ if env is None else env)
    return ConnectionBudget(_whole_number(env, "TELELAB_DB_POOL_SIZE", "5", 1, 200),
                            _whole_number(env, "TELELAB_DB_MAX_OVERFLOW", "10", 0, 200),
                            _whole_number(env, "TELELAB_WEB_HOSTS", "1", 1, 100))


def shared_dir(env: dict[str, str]) -> Path | None:
    """TELELAB_SHARED_DIR: an absolute folder every web host reads and writes (lesson videos and other uploads)."""
    raw = env.get("TELELAB_SHARED_DIR", "").strip()
    if not raw:
        return None
    if not Path(raw).is_absolute():
        raise ConfigError(f"TELELAB_SHARED_DIR must be an absolute path (a folder every web host mounts), not {raw!r}.")
    return Path(raw)


def from_environment(instance_dir: Path, environ: dict[str, str] | None = None) -> dict[str, object]:
    """The Flask config mapping built from TELELAB_* variables."""
    env = dict(os.environ if environ is None else environ)
    secure_cookie = env.get("TELELAB_SECURE_COOKIES", "0").lower() in {"1", "true", "yes"}
    idle = timedelta(minutes=_positive_number(env, "TELELAB_SESSION_IDLE_MINUTES", "120"))
    budget = connection_budget(env)
    return {
        "DATABASE_URL": env.get("TELELAB_DATABASE_URL", f"sqlite:///{instance_dir / 'telelab.sqlite3'}"),
        "SECRET_KEY": env.get("TELELAB_SECRET_KEY") or persistent_secret_key(instance_dir),
        "ROBOTS": parse_robots(env.get("TELELAB_ROBOTS", "")),
        "ROBOT_RPC_TIMEOUT_S": float(env.get("TELELAB_ROBOT_RPC_TIMEOUT_S", "1.0")),
        "ACCESS_GRACE_S": float(env.get("TELELAB_GRACE_S", "15")),
        "DEFAULT_TURN_LENGTH_S": float(env.get("TELELAB_DEFAULT_TURN_S", "120")),
        "ACCESS_TICK_S": float(env.get("TELELAB_ACCESS_TICK_S", "0.5")),
        "GROUND_TRUTH_ROLES": frozenset(
            r.strip() for r in env.get("TELELAB_GROUND_TRUTH_ROLES", "tutor,admin").split(",") if r.strip()
        ),
        "SESSION_COOKIE_HTTPONLY": True,
        "SESSION_COOKIE_SAMESITE": "Lax",
        # Always Secure when set; otherwise Secure whenever the request came over HTTPS (auth/cookies.py).
        "SESSION_COOKIE_SECURE": secure_cookie,
        "REMEMBER_COOKIE_SECURE": secure_cookie,
        "TRUSTED_PROXIES": trusted_proxies(env),
        "PREDICTION_CAP": prediction_cap(env),
        "SESSION_LIFETIME": timedelta(hours=_positive_number(env, "TELELAB_SESSION_HOURS", "8")),
        "SESSION_IDLE_TIMEOUT": idle,
        "PERMANENT_SESSION_LIFETIME": idle,  # the cookie's expiry slides with use, like the idle timeout
        # The auth blueprint renews the cookie every few minutes instead (re-signing it on every request cost
        # about 0.4 ms of each API call).
        "SESSION_REFRESH_EACH_REQUEST": False,
        "WTF_CSRF_TIME_LIMIT": None,  # the token lives as long as the session, which expires itself
        "MAX_CONTENT_LENGTH": 2 * 1024 * 1024,
        "DB_POOL_SIZE": budget.pool_size,
        "DB_MAX_OVERFLOW": budget.max_overflow,
        # Lesson videos and other uploads: a folder every web host reads (a shared mount with several hosts).
        # None: the instance folder, which is one host's (teaching/lessons.py: shared_dir).
        "SHARED_DIR": shared_dir(env),
    }
