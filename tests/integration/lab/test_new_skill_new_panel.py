"""A skill added to the skill server appears as a new panel, with no change to the middleware or client.

The skill server here runs in this process with one extra skill registered, exactly as a robot
team would add one to skill_server/skills/catalog.py; the middleware and the client are untouched.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from skill_server.goals import GoalFeedback
from skill_server.schema import ParameterSchema, ParameterType, SkillDescription
from skill_server.skills import catalog
from skill_server.skills.base import Outcome, SkillController, TickInput, succeeded
from tests.conftest import LabClient, LiveServer, _let_go, make_test_app
from tests.integration.lab.test_skills_api import api, take_control


class SpinInPlace(SkillController):
    """Spins at a given rate for a given time: a skill no part of the middleware or client knows."""

    def __init__(self, rate_radps: float, duration_s: float) -> None:
        super().__init__()
        self.rate_radps, self.duration_s, self.started_s = rate_radps, duration_s, None

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        if self.started_s is None:
            self.started_s = tick.sim_time_s
        elapsed = tick.sim_time_s - self.started_s
        progress = min(1.0, elapsed / self.duration_s)
        feedback = GoalFeedback(sim_time_s=tick.sim_time_s, state="spinning", progress=progress)
        if elapsed >= self.duration_s:
            return 0.0, 0.0, succeeded("Spun as asked."), feedback
        return 0.0, self.rate_radps, None, feedback


SPIN = SkillDescription(
    name="spin_in_place",
    title="Spin in place",
    help="Turns on the spot at a steady rate for a while.",
    parameters=(
        ParameterSchema("rate_radps", ParameterType.DOUBLE, "rad/s", 0.1, 1.0, 0.5, "How fast to spin."),
        ParameterSchema("duration_s", ParameterType.DOUBLE, "s", 0.1, 10.0, 1.0, "How long to spin."),
    ),
)


@pytest.fixture
def robot_with_a_new_skill(monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    from skill_server.server import create_server

    register_all = catalog.register_all

    def register_all_and_spin(registry, spec) -> None:
        register_all(registry, spec)
        registry.register(SPIN, SpinInPlace)

    monkeypatch.setattr(catalog, "register_all", register_all_and_spin)
    robot = create_server(port=0, robot_name="lab-9")
    try:
        yield robot.address
    finally:
        robot.stop()


def test_a_new_skill_gets_a_panel_and_runs_through_the_middleware(robot_with_a_new_skill: str, tmp_path: Path) -> None:

    app = make_test_app(f"sqlite:///{tmp_path / 'app.sqlite3'}", f"lab-1={robot_with_a_new_skill}", tmp_path)
    server = LiveServer(app)
    try:
        client = LabClient(server.url)
        assert client.login() == 302
        status, body = api(client, "GET", "/api/robots/lab-1/panels")
        panel = next(p for p in body["panels"] if p.get("skill") == "spin_in_place")
        assert panel["kind"] == "skill" and panel["title"] == "Spin in place"
        assert [p["name"] for p in panel["schema"]] == ["rate_radps", "duration_s"]
        assert panel["schema"][0]["maximum"] == 1.0 and panel["schema"][0]["unit"] == "rad/s"

        queue = take_control(client)
        telemetry = client.websocket("/ws/robots/lab-1/telemetry")
        before = _heading(telemetry)
        status, body = api(client, "POST", "/api/robots/lab-1/skills/spin_in_place/goals",
                           {"parameters": {"rate_radps": 0.8, "duration_s": 1.0}})
        assert status == 202, body
        goal_id = body["goal"]["goal_id"]
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline:
            goal = api(client, "GET", f"/api/robots/lab-1/goals/{goal_id}")[1]["goal"]
            if goal["status"] == "succeeded":
                break
            time.sleep(0.2)
        assert goal["status"] == "succeeded"
        turned = abs(math.remainder(_heading(telemetry) - before, 2 * math.pi))
        assert turned > 0.4, f"the new skill turned the robot {turned:.2f} rad"
        status, body = api(client, "POST", "/api/robots/lab-1/skills/spin_in_place/goals",
                           {"parameters": {"rate_radps": 5.0}})
        assert status == 400 and body["error"]["field"] == "rate_radps", "the server enforces the new schema"
        telemetry.close()
        queue.close()
    finally:
        server.stop()
        _let_go(app)  # its ticker, links, farm and practice keeper


def _heading(telemetry) -> float:
    latest = None
    while (message := telemetry.receive(timeout=0 if latest else 5)) is not None:
        data = json.loads(message)
        if data["type"] == "telemetry":
            latest = data
    return latest["odometry"]["pose"]["theta_rad"]


@pytest.fixture
def robot_with_a_new_sensor(monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    """A skill server whose robot describes one more sensor, as a robot team would add one to sim/panels.py."""
    from skill_server.server import create_server
    from skill_server.sim import world
    from skill_server.sim.panels import TELEBOT_PANELS, PanelSpec

    bumper = PanelSpec("bumpers", "bumpers", "Bumpers", "Which bumper touched something last.", "sense", "telemetry")
    monkeypatch.setattr(world, "TELEBOT_PANELS", (*TELEBOT_PANELS, bumper))
    robot = create_server(port=0, robot_name="lab-9")
    try:
        yield robot.address
    finally:
        robot.stop()


def test_a_new_sensor_gets_a_panel_through_the_contract_and_a_silent_robot_a_console_that_says_so(
        robot_with_a_new_sensor: str, tmp_path: Path) -> None:

    robots = f"lab-1={robot_with_a_new_sensor},lab-2=127.0.0.1:1"  # nothing listens on lab-2's port
    app = make_test_app(f"sqlite:///{tmp_path / 'app.sqlite3'}", robots, tmp_path)
    server = LiveServer(app)
    try:
        client = LabClient(server.url)
        assert client.login() == 302
        status, body = api(client, "GET", "/api/robots/lab-1/panels")
        assert status == 200 and body["notice"] == ""
        panel = next(p for p in body["panels"] if p["id"] == "bumpers")
        assert panel == {"id": "bumpers", "kind": "bumpers", "title": "Bumpers",
                         "channel": "/ws/robots/lab-1/telemetry", "help": "Which bumper touched something last.",
                         "tab": "sense"}
        assert {"camera", "odometry", "map", "sonar", "laser"} <= {p["id"] for p in body["panels"]}

        consoles = [LabClient(server.url) for _ in range(12)]  # a class opening its consoles at once
        assert all(console.login() == 302 for console in consoles)
        with ThreadPoolExecutor(len(consoles)) as pool:
            answers = list(pool.map(lambda console: api(console, "GET", "/api/robots/lab-1/panels"), consoles))
        assert all(status == 200 for status, _ in answers)
        assert all([p["id"] for p in answer["panels"]] == [p["id"] for p in body["panels"]] for _, answer in answers)

        status, body = api(client, "GET", "/api/robots/lab-2/panels")
        assert status == 200 and not body["skills_available"]
        assert {p["id"] for p in body["panels"]} == {"drive", "queue", "chat", "response-times"}
        assert "does not answer" in body["notice"]
    finally:
        server.stop()
        _let_go(app)  # its ticker, links, farm and practice keeper
