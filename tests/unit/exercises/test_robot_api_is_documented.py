"""Every call of the students' robot API (the public methods of telelab.py's Robot) is named where a student looks
for it: the exercise page's API sentence (in each language it speaks) and the table of docs/exercises.md."""

from __future__ import annotations

import inspect
import re
from pathlib import Path

from babel.messages.pofile import read_po

from tests.integration.exercises.world_backend import load_api

ROOT = Path(__file__).resolve().parents[3]
PAGE = ROOT / "client_ui" / "templates" / "exercises" / "exercise.html"
DOCS = ROOT / "docs" / "exercises.md"


def api_calls() -> set[str]:
    robot = load_api().Robot
    return {name for name, _ in inspect.getmembers(robot, inspect.isfunction) if not name.startswith("_")}


def page_sentence() -> str:
    """The page's sentence that lists the API (the paragraph under "Your program")."""
    found = re.search(r'_\("(Python, run by Pyodide[^"]*)"\)', PAGE.read_text(encoding="utf-8"))
    assert found, "the exercise page no longer lists the robot API"
    return found.group(1)


def test_the_page_and_the_guide_name_every_call_of_the_robot_api() -> None:
    calls = api_calls()
    assert {"tick", "odometry", "sonar", "laser", "bumper", "battery", "line", "set_velocity", "sleep", "run_skill",
            "start_skill", "localization"} <= calls
    sentence = page_sentence()
    with (ROOT / "middleware" / "translations" / "es" / "LC_MESSAGES" / "messages.po").open("rb") as po:
        spanish = read_po(po).get(sentence)
    assert spanish is not None and spanish.string, "the API sentence has no Spanish translation"
    guide = DOCS.read_text(encoding="utf-8")
    for where, text in (("the exercise page", sentence), ("its Spanish", spanish.string),
                        ("docs/exercises.md", guide)):
        missing = sorted(name for name in calls if not re.search(rf"\b{name}\(", text))
        assert not missing, f"{where} does not name {missing}"
