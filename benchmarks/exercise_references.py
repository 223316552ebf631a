"""The catalogue's reference solutions from the hidden random starts of many seeds: the success rate (full marks)
beside the accuracy each rubric measures, once with the sensors read as fast as the simulator steps and once as
the browser reads them (telemetry at 10 Hz, 0.1 s late).

    python -m benchmarks.exercise_references [--seeds N] [--slug follow-line ...]

Programs run under CPython against the robot API file the browser runs (client_ui/static/pages/exercises/
telelab.py), the simulator stepped as fast as it computes (tests/integration/exercises/world_backend.py), graded by
the server's own rubric (middleware/exercises/grading.py) over the true poses at the pose log's 5 Hz. Prints a
Markdown table (the one in middleware/exercises/README.md).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

from middleware.exercises.catalogue import BUILT_IN
from middleware.exercises.grading import grade, line_distance
from tests.integration.exercises import solutions
from tests.integration.exercises.skill_backend import run_with_skills
from tests.integration.exercises.world_backend import WorldBackend, random_start, run_code

REFERENCES = {"follow-line": solutions.FOLLOW_LINE, "kidnapped": solutions.KIDNAPPED}
ACCURACY = {"follow_line": "RMS off the line", "kidnapped": "reported pose error"}
CONDITIONS = (("as fast as it steps", 0.0, 0.0), ("as the browser reads it", 10.0, 0.1))


def accuracy(rubric: dict, run: WorldBackend, measured: list[float]) -> float:
    """The rubric's own accuracy figure [m]: for a line, the RMS distance of the robot's centre from it; for the
    kidnapping, the error of the pose the program reported."""
    if rubric["kind"] == "follow_line":
        return math.sqrt(statistics.fmean(line_distance(s[1], s[2], rubric) ** 2 for s in run.trace))
    return measured[0]


def run_reference(slug: str, exercise: dict, seed: int, telemetry_hz: float, latency_s: float) -> WorldBackend:
    """The reference's run from the hidden start of seed, placed as the server places the robot."""
    start = random_start(exercise["random_starts"], seed)
    if exercise["rubric"]["kind"] == "kidnapped":
        return run_with_skills(REFERENCES[slug], exercise["scene"], start, exercise["time_limit_s"], seed, True,
                               telemetry_hz, latency_s)
    return run_code(REFERENCES[slug], exercise["scene"], start, exercise["time_limit_s"], seed, telemetry_hz,
                    latency_s)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.exercise_references", description=__doc__)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--slug", action="append", choices=sorted(REFERENCES))
    args = parser.parse_args(argv)
    exercises = {entry["slug"]: entry for entry in BUILT_IN}
    print("| exercise | readings | seeds | success (100 %) | mean grade | mean measurements | accuracy | s/run |")
    print("|---|---|---|---|---|---|---|---|")
    for slug in args.slug or sorted(REFERENCES):
        exercise = exercises[slug]
        for label, telemetry_hz, latency_s in CONDITIONS:
            grades, accuracies, measured, took = [], [], [], []
            for seed in range(1, args.seeds + 1):
                began = time.monotonic()
                run = run_reference(slug, exercise, seed, telemetry_hz, latency_s)
                took.append(time.monotonic() - began)
                result = grade(exercise["rubric"], run.trace, run.reports[-1] if run.reports else None)
                grades.append(result.fraction)
                measured.append([m.value for m in result.measurements])
                accuracies.append(accuracy(exercise["rubric"], run, measured[-1]))
            means = [statistics.fmean(column) for column in zip(*measured, strict=True)]
            names = [m.name for m in result.measurements]
            print(f"| {slug} | {label} | {len(grades)} | {sum(g == 1.0 for g in grades)}/{len(grades)} | "
                  f"{statistics.fmean(grades):.2f} | "
                  + "; ".join(f"{n} {v:.2f}" for n, v in zip(names, means, strict=True))
                  + f" | {ACCURACY[exercise['rubric']['kind']]} {statistics.fmean(accuracies) * 100:.1f} cm "
                  f"(worst {max(accuracies) * 100:.1f}) | "
                  f"{statistics.fmean(took):.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
