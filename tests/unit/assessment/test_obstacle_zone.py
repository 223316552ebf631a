"""The "mark the obstacle zone" task: its truth from the robot's description, its answer's checks, and its grade
(IoU of cells, pass at 0.5): full marks for the true boxes, little or nothing for wrong ones."""

from __future__ import annotations

import math

import pytest

from middleware.assessment import obstacle_zone
from middleware.assessment.trace_grading import grade_task
from middleware.errors import Refused
from protos.telelab.v1 import robot_pb2
from skill_server.sim.scenes import get_scene


def lab_info() -> robot_pb2.RobotInfo:
    """The lab's RobotInfo boxes, as the skill server reports them."""
    boxes = [robot_pb2.SceneBox(name=b.name, center_x_m=b.center_x_m, center_y_m=b.center_y_m, half_x_m=b.half_x_m,
                                half_y_m=b.half_y_m, yaw_rad=b.yaw_rad) for b in get_scene("lab").scene_boxes()]
    return robot_pb2.RobotInfo(scene_boxes=boxes)


@pytest.fixture
def task() -> dict:
    return {"kind": obstacle_zone.TASK_KIND, "rubric": obstacle_zone.ZONE_RUBRIC, "points": 10,
            **obstacle_zone.scene_obstacles(lab_info())}


def rect_of(box: dict, grow_m: float = 0.0, shift_x_m: float = 0.0) -> list[float]:
    corners = obstacle_zone._corners(box)
    xs, ys = [c[0] for c in corners], [c[1] for c in corners]
    return [min(xs) - grow_m + shift_x_m, min(ys) - grow_m, max(xs) + grow_m + shift_x_m, max(ys) + grow_m]


def test_the_truth_leaves_the_walls_out_and_bounds_the_room(task: dict) -> None:
    assert {b["name"] for b in task["obstacles"]} == {"crate", "cabinet", "bench", "pillar"}
    assert task["bounds"] == pytest.approx([-4.1, -3.1, 4.1, 3.1])


def test_the_true_boxes_earn_full_marks(task: dict) -> None:
    zone = {"rects": [rect_of(box) for box in task["obstacles"]]}
    iou, precision, recall = obstacle_zone.zone_overlap(task, zone)
    assert iou == pytest.approx(1.0) and precision == recall == pytest.approx(1.0)
    result = grade_task(task, 10, [], zone)
    assert result.points == 10 and result.correct and "IoU 1.00" in result.feedback


def test_a_loose_but_right_zone_still_passes(task: dict) -> None:
    zone = {"rects": [rect_of(box, grow_m=0.1) for box in task["obstacles"]]}
    iou, precision, recall = obstacle_zone.zone_overlap(task, zone)
    assert 0.5 <= iou < 0.9 and recall == pytest.approx(1.0) and precision < 1.0
    assert grade_task(task, 10, [], zone).points == 10


@pytest.mark.parametrize(("rects", "most_points"), [
    ([[-3.5, -2.5, -3.0, -2.0], [3.0, -2.5, 3.5, -2.0]], 0.0),  # empty floor
    ([[-4.0, -3.0, 4.0, 3.0]], 0.0),  # the whole room
    ([[0.0, 0.0, 0.5, 0.5]], 0.0),  # the robot's own spot
])
def test_wrong_zones_earn_little_or_nothing(task: dict, rects: list[list[float]], most_points: float) -> None:
    result = grade_task(task, 10, [], {"rects": rects})
    assert result.points <= most_points and not result.correct, result.feedback


def test_half_the_obstacles_found_earns_part_of_the_points(task: dict) -> None:
    found = {"rects": [rect_of(box) for box in task["obstacles"][:2]]}
    result = grade_task(task, 10, [], found)
    assert 0 < result.points < 10 and not result.correct


def test_a_zone_shifted_off_the_obstacles_loses_marks(task: dict) -> None:
    shifted = {"rects": [rect_of(box, shift_x_m=0.5) for box in task["obstacles"]]}
    assert grade_task(task, 10, [], shifted).points < 10


def test_no_marks_earn_nothing_and_say_so(task: dict) -> None:
    for zone in (None, {}, {"rects": []}):
        result = grade_task(task, 10, [], zone)
        assert result.points == 0 and result.feedback == "No obstacle zone was marked."


@pytest.mark.parametrize(("answer", "field"), [
    ("here", "zone"),
    ({"rects": "all"}, "zone"),
    ({"rects": [[0, 0, 1, 1]] * 21}, "zone"),
    ({"rects": [[0, 0, 1]]}, "zone.rects[0]"),
    ({"rects": [[0, 0, 1, math.nan]]}, "zone.rects[0]"),
    ({"rects": [[0, 0, 1, 1], [0, 0, 1e9, 1]]}, "zone.rects[1]"),
    ({"rects": [[0, 0, True, 1]]}, "zone.rects[0]"),
    ({"rects": [[0, 0, "1", 1]]}, "zone.rects[0]"),
])
def test_a_malformed_zone_is_refused_naming_the_field(answer: object, field: str) -> None:
    with pytest.raises(Refused) as refused:
        obstacle_zone.clean_zone(answer)
    assert refused.value.status == 400 and refused.value.field == field


def test_a_zone_is_stored_with_its_corners_in_order() -> None:
    assert obstacle_zone.clean_zone({"rects": [[1, 2, -1, 0.5]]}) == {"rects": [[-1.0, 0.5, 1.0, 2.0]]}
