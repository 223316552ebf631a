"""A plan that reacts to a skill's event, run through the middleware on a real skill server (the practice robot,
from the dock of the lab scene, a wall ahead): the obstacle cuts the drive short, the on block backs away, the plan
goes on to its end, and the goal's channel carries each event as the console's event log shows it."""

from __future__ import annotations

import json
import time

import pytest

from tests.integration.plans.conftest import PlansLab, api, run_on_practice

REACTING = """on obstacle_detected 0.5 {
  say "Wall ahead: backing off"
  drive -0.2 0 for 1s
}
drive 0.5 0 for 30s
say "done"
"""


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_a_plan_reacts_to_an_obstacle_event_on_a_real_skill_server(plans_lab: PlansLab) -> None:
    ann = plans_lab.client("student1")
    status, created = api(ann, "POST", "/api/plans", {"name": "reacting", "text": REACTING})
    assert status == 201, created
    status, answer = run_on_practice(ann, created["plan"]["id"], {"beside": "lab-1", "from_dock": True})
    assert status == 202, answer
    channel = ann.websocket(answer["goal_channel"])
    events: list[tuple[str, str]] = []
    final = None
    deadline = time.monotonic() + 90
    while final is None and time.monotonic() < deadline:
        message = channel.receive(timeout=5)
        if message is None:
            continue
        data = json.loads(message)
        if data["type"] == "goal_event":
            events.append((data["kind"], data["message"]))
        elif data["type"] == "goal" and data["goal"]["status"] in ("succeeded", "aborted", "canceled"):
            final = data["goal"]
    channel.close()
    assert final is not None and final["status"] == "succeeded", (final, events)
    kinds = [kind for kind, _ in events]
    assert "obstacle_detected" in kinds and kinds.count("handled") == 1, events
    handled = next(message for kind, message in events if kind == "handled")
    assert handled.startswith("line 5 cut short by obstacle_detected (obstacle 0."), handled
    said = [message for kind, message in events if kind == "step_started"]
    assert said[-3:] == ["line 2: Wall ahead: backing off", "line 3: drive -0.2 m/s 0 rad/s for 1 s",
                         "line 6: done"], said
