"""Practice robots (cap, idle stop, owner-only control) and the lesson API, against real skill servers."""

from __future__ import annotations

import json
import subprocess
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from middleware.config import ConfigError
from middleware.robots.link import CommandRefused, RobotUnavailable
from middleware.teaching.practice_robots import PracticeCapReached, PracticeManager, read_limits


def _users(engine, *names: str) -> list[int]:
    from sqlalchemy.orm import sessionmaker

    from middleware.auth.services import create_user

    with sessionmaker(engine)() as session:
        ids = [create_user(session, name, "student", "correct-horse-battery").id for name in names]
        session.commit()
    return ids


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_the_cap_refuses_a_second_robot_and_idle_ones_are_stopped(engine) -> None:
    from sqlalchemy.orm import sessionmaker

    from middleware.farm.local import LocalProcessFarm

    ann, bob = _users(engine, "ann", "bob")
    now = [datetime(2026, 11, 25, 9, 0, tzinfo=UTC)]
    farm = LocalProcessFarm()
    manager = PracticeManager(farm, sessionmaker(engine), idle_s=60, cap=1, clock=lambda: now[0])
    try:
        robot = manager.start(ann, "ann")
        assert robot.name == "practice-ann" and manager.count() == 1
        assert manager.start(ann, "ann").link is robot.link  # asking again answers the running one
        with pytest.raises(PracticeCapReached, match="All 1 practice robots are in use"):
            manager.start(bob, "bob")
        assert robot.link.is_online()
        now[0] += timedelta(seconds=30)
        assert manager.stop_idle() == []
        now[0] += timedelta(seconds=31)
        assert manager.stop_idle() == ["practice-ann"]
        assert farm.find("practice-ann") is None and not robot.link.is_online()
        assert manager.count() == 0
    finally:
        manager.shutdown()
        farm.close()


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_a_lookup_in_a_request_writes_nothing_and_the_keeper_writes_the_use(engine) -> None:
    """Every request and channel of a practice robot looks it up; the lookup noted the use in a commit of its own,
    during the request (on SQLite, while the request held the write lock: WriteLockHeld). It is noted in memory and
    the keeper writes it, and the robot used through another worker is not idle."""
    from sqlalchemy import select, text
    from sqlalchemy.orm import sessionmaker

    from middleware.farm.local import LocalProcessFarm
    from middleware.models.farm import PersonalRobotRecord

    (ann,) = _users(engine, "ann")
    now = [datetime(2026, 11, 25, 9, 0, tzinfo=UTC)]
    sessions, farm = sessionmaker(engine), LocalProcessFarm()
    manager = PracticeManager(farm, sessions, idle_s=60, clock=lambda: now[0])
    other_worker = PracticeManager(farm, sessions, idle_s=60, clock=lambda: now[0])
    try:
        manager.start(ann, "ann")
        now[0] += timedelta(seconds=50)
        with sessions() as request, request.begin():
            request.execute(text("UPDATE users SET username = username WHERE id = :id"), {"id": ann})  # it wrote
            assert other_worker.get(ann) is not None  # the lookup commits nothing of its own
        with sessions() as session:
            written = session.scalar(select(PersonalRobotRecord.last_used_at))
        assert written.replace(tzinfo=UTC) == now[0] - timedelta(seconds=50)  # the use is not written yet
        other_worker.write_noted()  # the keeper's duty
        now[0] += timedelta(seconds=20)
        assert manager.stop_idle() == []  # used 20 s ago, through the other worker
        now[0] += timedelta(seconds=41)
        assert manager.stop_idle() == ["practice-ann"]
    finally:
        other_worker.close()
        manager.shutdown()
        farm.close()


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_a_practice_robot_killed_is_restarted_and_obeys_its_owner_again(engine) -> None:
    import os
    import signal
    import time

    from sqlalchemy.orm import sessionmaker

    from middleware.farm.local import LocalProcessFarm

    (ann,) = _users(engine, "ann")
    farm = LocalProcessFarm()
    manager = PracticeManager(farm, sessionmaker(engine), idle_s=600)
    try:
        robot = manager.start(ann, "ann")
        assert robot.link.drive(robot.token, 1, 0.1, 0.0).applied_sequence == 1
        os.kill(farm._processes["practice-ann"].process.pid, signal.SIGKILL)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            again = manager.get(ann)
            try:
                assert again is not None
                if again.link.drive(again.token, 2, 0.1, 0.0).applied_sequence == 2:
                    break
            except RobotUnavailable:
                time.sleep(0.3)
        else:
            pytest.fail("the restarted robot did not obey its owner's token within 30 s")
        assert farm.find("practice-ann").restarted
        with pytest.raises(CommandRefused):
            again.link.drive("someone-else", 3, 0.1, 0.0)
    finally:
        manager.shutdown()
        farm.close()


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_a_full_farm_is_a_clear_refusal_and_nothing_is_left_claimed(engine) -> None:
    from sqlalchemy.orm import sessionmaker

    from middleware.farm.local import LocalProcessFarm

    (ann,) = _users(engine, "ann")
    manager = PracticeManager(LocalProcessFarm(capacity=0), sessionmaker(engine), idle_s=600)
    with pytest.raises(PracticeCapReached, match="All 0 practice robots are in use"):
        manager.start(ann, "ann")
    assert manager.count() == 0


@pytest.mark.parametrize(("environ", "name"), [
    ({"TELELAB_PRACTICE_CAP": "many"}, "TELELAB_PRACTICE_CAP"),
    ({"TELELAB_PRACTICE_CAP": "-1"}, "TELELAB_PRACTICE_CAP"),
    ({"TELELAB_PRACTICE_CAP": "10001"}, "TELELAB_PRACTICE_CAP"),
    ({"TELELAB_PRACTICE_IDLE_S": "soon"}, "TELELAB_PRACTICE_IDLE_S"),
    ({"TELELAB_PRACTICE_IDLE_S": "1"}, "TELELAB_PRACTICE_IDLE_S"),
])
def test_bad_practice_settings_name_the_setting(environ: dict[str, str], name: str) -> None:
    with pytest.raises(ConfigError, match=name):
        read_limits(environ)


def _api(client, method: str, path: str, body: object | None = None):
    token = client.csrf_token("/teaching")
    data = None if body is None else json.dumps(body).encode()
    from urllib.request import Request

    request = Request(client.base_url + path, data=data, method=method,
                      headers={"Content-Type": "application/json", "X-CSRFToken": token, "Accept": "application/json"})
    try:
        with client._opener.open(request, timeout=20) as response:
            return response.status, json.loads(response.read())
    except Exception as error:  # noqa: BLE001 - 4xx/5xx are answers here
        return error.code, json.loads(error.read())


@pytest.fixture
def tutor_client(live_server, lab_client):
    from middleware.auth.services import create_user
    from middleware.db import session_factory

    with session_factory(live_server.app)() as session:
        create_user(session, "tutor1", "tutor", "correct-horse-battery")
        session.commit()
    assert lab_client.login("tutor1", "correct-horse-battery") == 302
    return lab_client


def test_cap_reached_over_http_is_a_clear_message(live_server, tutor_client) -> None:
    from middleware.teaching.practice_robots import practice_manager

    practice_manager(live_server.app).cap = 0
    status, body = _api(tutor_client, "POST", "/api/practice")
    assert status == 429
    assert body["error"]["code"] == "practice_cap_reached" and "in use" in body["error"]["message"]


def test_a_lesson_is_checked_saved_and_drives_only_the_owners_practice_robot(live_server, tutor_client) -> None:
    from middleware.teaching.practice_robots import practice_manager

    folder = Path(live_server.app.instance_path) / "lessons"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "clip.webm").write_bytes(b"not really a video")
    track = ('WEBVTT\n\n00:00:01.000 --> 00:00:03.000\n{"skill": "go_to_goal", "parameters": {"goal_x_m": 0.4, '
             '"goal_y_m": 0.0}}\n\n00:00:04.000 --> 00:00:05.000\n{"skill": "go_to_goal", "parameters": '
             '{"speed_mps": 9}}\n')
    status, body = _api(tutor_client, "POST", "/api/lessons", {"title": "Goal", "video_name": "clip.webm",
                                                               "cues": track})
    assert status == 400 and body["errors"][0] == {"line": 7, "field": "parameters.speed_mps",
                                                   "message": body["errors"][0]["message"]}
    status, body = _api(tutor_client, "POST", "/api/lessons", {"title": "Goal", "video_name": "../secret",
                                                               "cues": track})
    assert status == 400 and body["error"]["field"] == "video_name"
    good = track.split("\n\n00:00:04")[0] + "\n"
    status, lesson = _api(tutor_client, "POST", "/api/lessons", {"title": "Goal", "video_name": "clip.webm",
                                                                 "cues": good})
    assert status == 201 and lesson["cues"][0]["command"]["skill"] == "go_to_goal"

    status, body = _api(tutor_client, "POST", f"/api/lessons/{lesson['id']}/cues/1/run", {"target": "practice"})
    assert status == 409 and body["error"]["code"] == "no_practice_robot"
    status, body = _api(tutor_client, "POST", f"/api/lessons/{lesson['id']}/cues/1/run", {"target": "lab-1"})
    assert status == 403 and body["error"]["field"] == "target"

    practice_manager(live_server.app).cap = 1
    try:
        status, started = _api(tutor_client, "POST", "/api/practice")
        assert status == 202 and started["starting"] and started["name"] == "practice-tutor1"
        status, ran = _api(tutor_client, "POST", f"/api/lessons/{lesson['id']}/cues/1/run",
                           {"target": "practice", "hold_s": 2})
        assert status == 202 and ran["goal"]["status"] in {"accepted", "executing"}
        assert ran["middleware_to_ack_ms"] >= 0
        status, stopped = _api(tutor_client, "POST", "/api/lessons/stop", {"target": "practice"})
        assert status == 200 and stopped["applied_sequence"] is not None
        status, goal = _api(tutor_client, "GET", f"/api/robots/practice/command-goals/{ran['goal']['goal_id']}")
        assert status == 200 and goal["goal"]["status"] == "canceled"  # the stop preempted the cue's goal
        status, body = _api(tutor_client, "POST", f"/api/lessons/{lesson['id']}/cues/9/run", {"target": "practice"})
        assert status == 404 and body["error"]["field"] == "index"
        status, body = _api(tutor_client, "POST", f"/api/lessons/{lesson['id']}/cues/1/run",
                            {"target": "practice", "hold_s": "forever"})
        assert status == 400 and body["error"]["field"] == "hold_s"
    finally:
        _api(tutor_client, "DELETE", "/api/practice")
        practice_manager(live_server.app).shutdown()


def test_ffmpeg_is_available_for_the_demo_video() -> None:
    assert subprocess.run(["ffmpeg", "-version"], capture_output=True).returncode == 0


def test_the_demo_tours_are_seeded_once_and_pass_the_real_skill_schemas(app) -> None:
    from middleware.robots.registry import robot_registry
    from middleware.teaching.demo_content import DEMO_TOURS, seed_demo_content
    from middleware.teaching.targets import skill_schemas
    from middleware.teaching.tours import check_tour

    schemas = skill_schemas(robot_registry(app).get("lab-1"))
    for tour in DEMO_TOURS:
        check_tour(tour, schemas)
    assert len(seed_demo_content(app, record_video=False)) == len(DEMO_TOURS)
    assert seed_demo_content(app, record_video=False) == []
