"""Scenes by name, the robot's URDF, and the core's independence from gRPC."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import skill_server
from skill_server.errors import UnknownScene
from skill_server.sim import robot_model
from skill_server.sim.scenes import get_scene, known_scenes
from skill_server.sim.world import World

CORE_PACKAGES = ("sim", "skills")


def test_an_unknown_scene_is_refused_listing_the_known_ones() -> None:
    with pytest.raises(UnknownScene) as refused:
        World("moon-base", realtime=False)
    message = str(refused.value)
    assert "moon-base" in message and "lab" in message and "empty" in message


def test_the_lab_is_an_8_by_6_room_with_walls_and_obstacles() -> None:
    lab = get_scene("lab")
    names = {box.name for box in lab.scene_boxes()}
    assert {"wall_east", "wall_west", "wall_north", "wall_south", "pillar"} <= names
    assert len(names) >= 7
    assert (2 * lab.floor_half_x_m, 2 * lab.floor_half_y_m) == (8.0, 6.0)
    assert len(lab.marks) > 10
    assert "lab" in known_scenes()


def test_the_urdf_file_is_generated_from_the_robot_spec() -> None:
    assert robot_model.URDF_PATH.read_text() == robot_model.urdf_text(robot_model.TELEBOT)


def test_the_robot_figures_are_those_of_a_small_round_base() -> None:
    spec = robot_model.TELEBOT
    assert 0.18 <= spec.body_radius_m <= 0.25
    assert (spec.max_linear_mps, spec.max_angular_radps) == (0.5, 1.5)


def test_wheel_speeds_follow_differential_drive_kinematics() -> None:
    spec = robot_model.TELEBOT
    left, right = robot_model.wheel_speeds_radps(spec, 0.5, 0.0)
    assert left == right == pytest.approx(0.5 / spec.wheel_radius_m)
    left, right = robot_model.wheel_speeds_radps(spec, 0.0, 1.0)
    assert right == -left == pytest.approx(spec.wheel_base_m / 2 / spec.wheel_radius_m)


def _imported_modules(path: Path) -> set[str]:
    modules: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            modules.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            modules.add(node.module)
    return modules


@pytest.mark.parametrize("package", CORE_PACKAGES)
def test_the_robot_core_imports_neither_grpc_nor_the_protos(package: str) -> None:
    root = Path(skill_server.__file__).parent / package
    for path in root.rglob("*.py"):
        for module in _imported_modules(path):
            assert not module.startswith(("grpc", "protos", "middleware")), f"{path} imports {module}"
