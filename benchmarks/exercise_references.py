"""The catalogue's reference solutions from the hidden random starts of many seeds: the success rate (full marks)
beside the accuracy each rubric measures, once with the sensors read as fast as the simulator steps and once as
the browser reads them (telemetry at 10 Hz, 0.1 s late).

    python -m benchmarks.exercise_references [--seeds N] [--slug follow-line ...] [--starts anywhere]

Programs run under CPython against the robot API file the browser runs (client_ui/static/pages/exercises/
telelab.py), the simulator stepped as fast as it computes (tests/integration/exercises/world_backend.py), graded by
the server's own rubric (middleware/exercises/grading.py) over the true poses at the pose log's 5 Hz. Prints a
Markdown table (the one in middleware/exercises/README.md).

`kidnapped-go-to-goal` is the kidnapping's reference with the drive to the goal left to the robot's go_to_goal
skill; `--starts anywhere` draws the kidnappings' starts from the whole lab's floor (clear of every obstacle by
ANYWHERE_CLEARANCE_M) instead of the exercise's hidden region.
"""

from __future__ import annotations

import argparse
import math
import random
import statistics
import time

from middleware.exercises.catalogue import BUILT_IN
from middleware.exercises.grading import grade, line_distance
from skill_server.errors import InvalidParameter
from skill_server.sim.geometry import Pose2D
from skill_server.sim.placement import check_placement
from skill_server.sim.robot_model import TELEBOT
from skill_server.sim.scenes import get_scene
from tests.integration.exercises import solutions
from tests.integration.exercises.skill_backend import run_with_skills
from tests.integration.exercises.world_backend import WorldBackend, random_start, run_code

# The kidnapping's reference up to its report, then the robot's own go_to_goal (it plans in the known map once the
# localization found the robot: the echoes drawn while it was lost are dropped).
KIDNAPPED_GO_TO_GOAL = solutions.KIDNAPPED.split("# Drive to the goal")[0] + \
    'print("go_to_goal:", robot.run_skill("go_to_goal", goal_x_m=GOAL[0], goal_y_m=GOAL[1], max_error_m=0.1))\n'
REFERENCES = {"bump-and-go": solutions.BUMP_AND_GO, "wall-following": solutions.WALL_FOLLOWING,
              "obstacle-avoidance": solutions.OBSTACLE_AVOIDANCE, "cover-room": solutions.COVER_ROOM,
              "follow-line": solutions.FOLLOW_LINE, "kidnapped": solutions.KIDNAPPED,
              "kidnapped-go-to-goal": KIDNAPPED_GO_TO_GOAL}
SLUG_OF = {"kidnapped-go-to-goal": "kidnapped"}  # a variant's exercise
ANYWHERE_CLEARANCE_M = 0.15  # beyond the body's radius, from every wall and obstacle
ACCURACY = {"follow_line": "RMS off the line", "kidnapped": "reported pose error"}
CONDITIONS = (("as fast as it steps", 0.0, 0.0), ("as the browser reads it", 10.0, 0.1))


def accuracy(rubric: dict, run: WorldBackend, measured: list[float]) -> float:
    """The rubric's own accuracy figure [m]: for a line, the RMS distance of the robot's centre from it; for the
    kidnapping, the error of the pose the program reported."""
    if rubric["kind"] == "follow_line":
        return math.sqrt(statistics.fmean(line_distance(s[1], s[2], rubric) ** 2 for s in run.trace))
    return measured[0]


def start_anywhere(scene_name: str, seed: int) -> list[float]:
    """A start drawn from the whole floor of the scene, the body clear of everything by ANYWHERE_CLEARANCE_M."""
    scene, draw = get_scene(scene_name), random.Random(seed)
    while True:
        start = [draw.uniform(-scene.floor_half_x_m, scene.floor_half_x_m),
                 draw.uniform(-scene.floor_half_y_m, scene.floor_half_y_m), draw.uniform(-math.pi, math.pi)]
        try:
            check_placement(scene, Pose2D(*start), TELEBOT.body_radius_m + ANYWHERE_CLEARANCE_M)
        except InvalidParameter:
            continue
        return start


def run_reference(slug: str, exercise: dict, seed: int, telemetry_hz: float, latency_s: float,
                  anywhere: bool = False) -> WorldBackend:
    """The reference's run from the hidden start of seed (or from anywhere on the floor), placed as the server places
    the robot."""
    start = start_anywhere(exercise["scene"], seed) if anywhere else random_start(exercise["random_starts"], seed)
    if exercise["rubric"]["kind"] == "kidnapped":
        return run_with_skills(REFERENCES[slug], exercise["scene"], start, exercise["time_limit_s"], seed, True,
                               telemetry_hz, latency_s)
    return run_code(REFERENCES[slug], exercise["scene"], start, exercise["time_limit_s"], seed, telemetry_hz,
                    latency_s)


def _accuracy_cell(kind: str, accuracies: list[float]) -> str:
    """The rubric's accuracy figure, mean (worst), for the kinds that have one (the others' measurements say it)."""
    if kind not in ACCURACY:
        return "—"
    return f"{ACCURACY[kind]} {statistics.fmean(accuracies) * 100:.1f} cm (worst {max(accuracies) * 100:.1f})"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.exercise_references", description=__doc__)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--slug", action="append", choices=sorted(REFERENCES))
    parser.add_argument("--starts", choices=("hidden", "anywhere"), default="hidden",
                        help="the exercise's hidden start region, or anywhere on the lab's floor")
    args = parser.parse_args(argv)
    exercises = {entry["slug"]: entry for entry in BUILT_IN}
    print("| exercise | starts | readings | seeds | success (100 %) | mean grade | mean measurements | accuracy | "
          "s/run |")
    print("|---|---|---|---|---|---|---|---|---|")
    for slug in args.slug or sorted(REFERENCES):
        exercise = exercises[SLUG_OF.get(slug, slug)]
        for label, telemetry_hz, latency_s in CONDITIONS:
            grades, accuracies, measured, took = [], [], [], []
            for seed in range(1, args.seeds + 1):
                began = time.monotonic()
                run = run_reference(slug, exercise, seed, telemetry_hz, latency_s, args.starts == "anywhere")
                took.append(time.monotonic() - began)
                result = grade(exercise["rubric"], run.trace, run.reports[-1] if run.reports else None)
                grades.append(result.fraction)
                measured.append([m.value for m in result.measurements])
                if exercise["rubric"]["kind"] in ACCURACY:
                    accuracies.append(accuracy(exercise["rubric"], run, measured[-1]))
            means = [statistics.fmean(column) for column in zip(*measured, strict=True)]
            names = [m.name for m in result.measurements]
            print(f"| {slug} | {args.starts} | {label} | {len(grades)} | "
                  f"{sum(g == 1.0 for g in grades)}/{len(grades)} | {statistics.fmean(grades):.2f} | "
                  + "; ".join(f"{n} {v:.2f}" for n, v in zip(names, means, strict=True))
                  + f" | {_accuracy_cell(exercise['rubric']['kind'], accuracies)} | "
                  f"{statistics.fmean(took):.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
