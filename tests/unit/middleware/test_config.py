"""Configuration from the environment: robots parse, mistakes are named."""

from __future__ import annotations

from datetime import timedelta
from pathlib import Path

import pytest

from middleware.config import ConfigError, RobotAddress, from_environment, parse_robots


def test_robots_parse_in_order() -> None:
    assert parse_robots("lab-1=127.0.0.1:50051, lab-2 = host:7") == (
        RobotAddress("lab-1", "127.0.0.1:50051"), RobotAddress("lab-2", "host:7"),
    )
    assert parse_robots("") == ()


@pytest.mark.parametrize(("name", "title"), [("lab-1", "Lab 1"), ("course-a", "Course A"), ("LAB_2", "Lab 2"),
                                             ("practice-bob", "Practice bob")])
def test_robot_titles_come_from_their_names(name: str, title: str) -> None:
    assert RobotAddress(name, "h:1").title == title


@pytest.mark.parametrize("value", ["lab-1", "lab-1=nohostport", "=127.0.0.1:1", "bad name=h:1", "a=h:1,a=h:2"])
def test_bad_robot_entries_name_the_setting(value: str) -> None:
    with pytest.raises(ConfigError, match="TELELAB_ROBOTS"):
        parse_robots(value)


def test_secret_key_is_generated_once_and_kept(tmp_path: Path) -> None:
    first = from_environment(tmp_path, {})
    second = from_environment(tmp_path, {})
    assert first["SECRET_KEY"] == second["SECRET_KEY"] and len(str(first["SECRET_KEY"])) > 40
    assert (tmp_path / "secret_key").stat().st_mode & 0o077 == 0
    assert from_environment(tmp_path, {"TELELAB_SECRET_KEY": "given"})["SECRET_KEY"] == "given"
    assert str(first["DATABASE_URL"]).startswith("sqlite:///")


def test_session_limits_and_proxy_trust_have_sane_defaults(tmp_path: Path) -> None:
    config = from_environment(tmp_path, {"TELELAB_SECRET_KEY": "k"})
    assert config["SESSION_LIFETIME"] == timedelta(hours=8)
    assert config["SESSION_IDLE_TIMEOUT"] == config["PERMANENT_SESSION_LIFETIME"] == timedelta(minutes=120)
    assert config["TRUSTED_PROXIES"] == 0 and config["SESSION_COOKIE_SECURE"] is False
    tuned = from_environment(tmp_path, {"TELELAB_SECRET_KEY": "k", "TELELAB_SESSION_HOURS": "2",
                                        "TELELAB_SESSION_IDLE_MINUTES": "15", "TELELAB_TRUSTED_PROXIES": "1"})
    assert tuned["SESSION_LIFETIME"] == timedelta(hours=2) and tuned["SESSION_IDLE_TIMEOUT"] == timedelta(minutes=15)
    assert tuned["TRUSTED_PROXIES"] == 1


@pytest.mark.parametrize(("name", "value"), [
    ("TELELAB_SESSION_HOURS", "0"), ("TELELAB_SESSION_HOURS", "-1"), ("TELELAB_SESSION_HOURS", "nan"),
    ("TELELAB_SESSION_HOURS", "inf"), ("TELELAB_SESSION_IDLE_MINUTES", "ten"), ("TELELAB_TRUSTED_PROXIES", "-1"),
    ("TELELAB_TRUSTED_PROXIES", "6"), ("TELELAB_TRUSTED_PROXIES", "one"),
])
def test_bad_session_and_proxy_settings_name_the_setting(tmp_path: Path, name: str, value: str) -> None:
    with pytest.raises(ConfigError, match=name):
        from_environment(tmp_path, {"TELELAB_SECRET_KEY": "k", name: value})


def test_the_prediction_cap_defaults_to_two_and_names_itself_when_wrong(tmp_path: Path) -> None:
    assert from_environment(tmp_path, {"TELELAB_SECRET_KEY": "k"})["PREDICTION_CAP"] == 2
    none = from_environment(tmp_path, {"TELELAB_SECRET_KEY": "k", "TELELAB_PREDICTION_CAP": " 0 "})
    assert none["PREDICTION_CAP"] == 0
    for wrong in ("-1", "65", "two", "1.5", "٣", ""):
        with pytest.raises(ConfigError, match="TELELAB_PREDICTION_CAP"):
            from_environment(tmp_path, {"TELELAB_SECRET_KEY": "k", "TELELAB_PREDICTION_CAP": wrong})
