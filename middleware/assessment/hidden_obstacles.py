"""While a student's obstacle-zone test is in progress, nothing the middleware sends them shows the scene's obstacles
(issue 16): the exercise is to find them from accumulated sonar and laser readings. This module is the rule's one
owner; the lab's routes and channels ask it.

The rule holds for that student on every robot (another lab robot or their practice robot may run the same scene)
from the attempt's start until it ends (submitted, or its deadline passed). Walls stay (obstacle_zone.WALL_PREFIX):
the room's edge is not the exercise. Tutors, admins and other students are not concerned.
"""

from __future__ import annotations

from datetime import datetime
from typing import Any

from sqlalchemy import or_, select
from sqlalchemy.orm import Session

from middleware.assessment.obstacle_zone import TASK_KIND, is_wall
from middleware.models.assessment import Attempt, Exam

OBSTACLES_HIDDEN = "obstacles_hidden"  # the stable code of every refusal and the scene's field naming the rule
HIDDEN_NOTE = ("Obstacles hidden during your obstacle-zone test: find them from the sonar and laser readings. "
               "They come back when you submit.")
CAMERA_REFUSAL = ("No camera during your obstacle-zone test: the picture would show the obstacles. Find them from "
                  "the sonar and laser readings; the camera comes back when you submit.")
MAP_REFUSAL = ("No map during your obstacle-zone test: a map can hold the lab's floor plan. Find the obstacles "
               "from the sonar and laser readings; the map comes back when you submit.")
HIDDEN_VERSION_SUFFIX = "-obstacles-hidden"  # a scene version (its ETag) of its own: a cached full one is not reused


def hides_obstacles(session: Session, user_id: int, now: datetime) -> bool:
    """Whether user_id has an obstacle-zone attempt in progress now (on any robot): then they see no obstacles."""
    tasks = session.scalars(select(Exam.task).join(Attempt, Attempt.exam_id == Exam.id).where(
        Attempt.user_id == user_id, Attempt.status == "in_progress", Exam.kind == "experimental",
        or_(Attempt.deadline_at.is_(None), Attempt.deadline_at > now)))
    return any(isinstance(task, dict) and task.get("kind") == TASK_KIND for task in tasks)


def scene_without_obstacles(scene: dict[str, Any]) -> dict[str, Any]:
    """The scene route's answer with only the walls among its blocks and cylinders, saying so in `obstacles_hidden`."""
    return {**scene, "version": f"{scene.get('version', '')}{HIDDEN_VERSION_SUFFIX}",
            "blocks": [block for block in scene.get("blocks", []) if is_wall(str(block.get("name", "")))],
            "cylinders": [cylinder for cylinder in scene.get("cylinders", [])
                          if is_wall(str(cylinder.get("name", "")))],
            OBSTACLES_HIDDEN: HIDDEN_NOTE}


def info_without_obstacles(info: dict[str, Any]) -> dict[str, Any]:
    """The robot's description with only the walls among its scene boxes, saying so in `obstacles_hidden`."""
    return {**info, "scene_boxes": [box for box in info.get("scene_boxes", []) if is_wall(str(box.get("name", "")))],
            OBSTACLES_HIDDEN: HIDDEN_NOTE}
