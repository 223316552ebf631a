"""`telelab up`'s robots: the lab robots in their scene, then one robot per experiment course."""

from __future__ import annotations

from middleware.lab_runner import lab_robots


def test_the_lab_starts_its_robots_and_one_robot_per_course() -> None:
    robots = lab_robots(2, "lab")
    assert [(r.name, r.scene) for r in robots] == [
        ("lab-1", "lab"), ("lab-2", "lab"), ("course-a", "course-A"), ("course-b", "course-B"),
    ]
    assert all(r.process is None for r in robots)  # described, not started


def test_the_course_robots_can_be_left_out() -> None:
    assert [r.name for r in lab_robots(1, "lab", course_robots=False)] == ["lab-1"]
