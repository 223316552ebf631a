"""Tour steps: checked against the robot's skills, errors naming the field."""

from __future__ import annotations

import pytest

from middleware.teaching.demo_content import DEMO_TOURS
from middleware.teaching.tours import TourInvalid, check_tour, parse_step

SKILLS = {"go_to_goal": [{"name": "goal_x_m", "type": "double", "minimum": -50.0, "maximum": 50.0, "choices": []}]}


def test_a_step_with_a_skill_and_its_condition() -> None:
    step = parse_step({"text": "Go", "panel": "skill-go_to_goal", "command": {"skill": "go_to_goal",
                       "parameters": {"goal_x_m": 1}}, "condition": {"type": "skill_finished"}}, "steps[0]", SKILLS)
    assert step.condition == "skill_finished" and step.command is not None


@pytest.mark.parametrize(("step", "field"), [
    ({"panel": "camera"}, "steps[0].text"),
    ({"text": "x", "panel": "<img>"}, "steps[0].panel"),
    ({"text": "x", "panel": "map", "command": {"skill": "fly"}}, "steps[0].command.skill"),
    ({"text": "x", "panel": "map", "command": {"skill": "go_to_goal", "parameters": {"goal_x_m": 99}}},
     "steps[0].command.parameters.goal_x_m"),
    ({"text": "x", "panel": "map", "condition": {"type": "time", "seconds": 0}}, "steps[0].condition.seconds"),
    ({"text": "x", "panel": "map", "condition": {"type": "time", "seconds": True}}, "steps[0].condition.seconds"),
    ({"text": "x", "panel": "map", "condition": {"type": "skill_finished"}}, "steps[0].condition"),
    ({"text": "x", "panel": "map", "condition": {"type": "eval"}}, "steps[0].condition"),
    ({"text": "x", "panel": "map", "onload": "x"}, "steps[0].onload"),
    ({"text": "x" * 2001, "panel": "map"}, "steps[0].text"),
])
def test_bad_steps_name_the_field(step: dict[str, object], field: str) -> None:
    with pytest.raises(TourInvalid) as raised:
        check_tour({"title": "T", "steps": [step]}, SKILLS)
    assert raised.value.field == field


@pytest.mark.parametrize("steps", [[], None, "x", [{}] * 51])
def test_a_tour_needs_one_to_fifty_steps(steps: object) -> None:
    with pytest.raises(TourInvalid) as raised:
        check_tour({"title": "T", "steps": steps}, SKILLS)
    assert raised.value.field in {"steps", "steps[0].text"}


def test_the_demo_tours_are_valid_in_form() -> None:
    for tour in DEMO_TOURS:
        check_tour(tour, None)


def test_panel_choices_name_the_console_panels_and_skills_by_title_and_keep_ids_in_use() -> None:
    from middleware.lab.panels import robot_panels
    from middleware.teaching.tours import panel_choices
    from tests.unit.lab.test_robot_panels import telebot_info

    described = robot_panels("r", telebot_info(), None)
    choices = dict(panel_choices(described, {"wall_following": [], "go_to_goal": []}, ["old-panel"]))
    assert choices["map"] == "Lab model" and choices["camera"] == "Camera"
    assert choices["skill-go_to_goal"] == "Go to goal" and choices["skill-wall_following"] == "Wall following"
    assert choices["old-panel"] == "old-panel"
