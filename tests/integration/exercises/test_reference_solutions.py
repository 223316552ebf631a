"""Each catalogue exercise's rubric, graded from the simulator's ground truth, gives a reference solution full marks
from the hidden random starts of several seeds and a wrong solution little: a rubric that cannot fail shows here.

The programs run under CPython against the same robot API file the browser runs in Pyodide
(client_ui/static/pages/exercises/telelab.py), whose backend here steps the real simulator (skill_server/sim) as
fast as it computes instead of talking to the page; the grade is the server's own (middleware/exercises/grading.py)
over the true poses sampled at the robot's pose-log rate."""

from __future__ import annotations

import pytest

from middleware.exercises.catalogue import BUILT_IN
from middleware.exercises.grading import grade
from tests.integration.exercises import solutions
from tests.integration.exercises.world_backend import random_start, run_code

EXERCISES = {entry["slug"]: entry for entry in BUILT_IN}
SOLUTIONS = {"bump-and-go": (solutions.BUMP_AND_GO, solutions.BUMP_AND_GO_WRONG),
             "wall-following": (solutions.WALL_FOLLOWING, solutions.WALL_FOLLOWING_WRONG),
             "obstacle-avoidance": (solutions.OBSTACLE_AVOIDANCE, solutions.OBSTACLE_AVOIDANCE_WRONG),
             "cover-room": (solutions.COVER_ROOM, solutions.COVER_ROOM_WRONG),
             "follow-line": (solutions.FOLLOW_LINE, solutions.FOLLOW_LINE_WRONG)}
SEEDS = (11, 12)  # two hidden starts each: the suite's time is shared (three were checked while writing them)
LITTLE = 0.34  # at most a third of the points for a wrong solution


def test_every_catalogue_exercise_has_a_reference_and_a_wrong_solution() -> None:
    assert set(SOLUTIONS) == set(EXERCISES)


@pytest.mark.parametrize("slug", sorted(SOLUTIONS))
def test_the_reference_earns_full_marks_from_hidden_starts_and_a_wrong_solution_little(slug: str, capsys) -> None:
    exercise = EXERCISES[slug]
    right, wrong = SOLUTIONS[slug]
    for seed in SEEDS:
        start = random_start(exercise["random_starts"], seed)
        run = run_code(right, exercise["scene"], start, exercise["time_limit_s"], seed)
        result = grade(exercise["rubric"], run.trace)
        assert result.fraction == 1.0, f"{slug}, seed {seed}, start {start}: {result.feedback}"
    start = random_start(exercise["random_starts"], SEEDS[0])
    run = run_code(wrong, exercise["scene"], start, exercise["time_limit_s"], SEEDS[0])
    result = grade(exercise["rubric"], run.trace)
    assert result.fraction <= LITTLE, f"{slug}: a wrong solution earned {result.feedback}"
    capsys.readouterr()  # the programs' prints


def test_the_api_refuses_a_velocity_beyond_the_robots_limits_before_it_leaves() -> None:
    exercise = EXERCISES["bump-and-go"]
    too_fast = "from telelab import robot\nrobot.tick()\nrobot.set_velocity(5.0, 0.0)\n"
    with pytest.raises(ValueError, match="linear_mps must be within"):
        run_code(too_fast, exercise["scene"], exercise["start"], 2.0, 1)


def test_tick_ends_the_loop_at_the_time_limit_and_stops_the_wheels() -> None:
    exercise = EXERCISES["bump-and-go"]
    forever = "from telelab import robot\nwhile robot.tick():\n    robot.set_velocity(0.3, 0.0)\n"
    run = run_code(forever, exercise["scene"], exercise["start"], 3.0, 1)
    assert 2.9 <= run.now() <= 3.1
    assert run.last_sent == (0.0, 0.0)  # the last command sent was a stop
