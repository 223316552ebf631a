"""A sequence's later steps go back to where it started, in the frame of the pose the skills steer by then. In the
near-obstacle round trips a trip started on odometry (14.5 cm and 8.5 degrees off after 12 s beside an obstacle);
localization converged 0.2 s later, and the way back went to the odometry coordinates in the localized frame:
"reached" while 12.9 cm from the start. The start is placed again at the first tick of the new frame."""

from __future__ import annotations

import math

from skill_server.goals import EventKind, GoalFeedback
from skill_server.sim.geometry import Pose2D
from skill_server.sim.odometry import OdometryReading
from skill_server.skills.base import Outcome, SkillController, TickInput, feedback_for, succeeded
from skill_server.skills.sequence import StepSequence


class RecordsItsStart(SkillController):
    """A step that notes the start it was built with and succeeds at once."""

    def __init__(self, start: Pose2D, seen: list[Pose2D]) -> None:
        super().__init__()
        seen.append(start)

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        return 0.0, 0.0, succeeded("done"), feedback_for(tick, "done", 1.0)


def tick_at(odometry: Pose2D, believed: Pose2D, source: str, time_s: float) -> TickInput:
    return TickInput(time_s, 0.025, OdometryReading(odometry, 0.0, 0.0), (), (), False, believed, source,
                     None, None)  # type: ignore[arg-type]


def run_two_steps(first: TickInput, second: TickInput) -> tuple[list[Pose2D], list[tuple[EventKind, str]]]:
    seen: list[Pose2D] = []
    sequence = StepSequence([("out", lambda start: RecordsItsStart(start, seen)),
                             ("back", lambda start: RecordsItsStart(start, seen))])
    sequence.tick(first)
    step = sequence.tick(second)
    return seen, list(step.events)


def test_the_same_pose_source_keeps_the_start_as_it_was_believed() -> None:
    start = Pose2D(1.0, 1.0, 0.0)
    seen, events = run_two_steps(tick_at(Pose2D(0.9, 1.1, 0.05), start, "localization", 0.0),
                                 tick_at(Pose2D(2.0, 1.3, 0.1), Pose2D(2.0, 1.0, 0.0), "localization", 5.0))
    assert seen == [start, start]
    assert not [message for _, message in events if "placed again" in message]


def test_a_start_taken_on_odometry_is_placed_again_by_the_odometry_since_once_localization_takes_over() -> None:
    # Odometry had drifted 0.15 m in y before the start; the truth started at (1, 1). The robot then drove 2 m
    # along x (odometry and the truth agree on that), and localization converged on the true pose (3, 1).
    on_odometry = Pose2D(1.0, 1.15, 0.0)
    seen, events = run_two_steps(tick_at(on_odometry, on_odometry, "odometry", 0.0),
                                 tick_at(Pose2D(3.0, 1.15, 0.0), Pose2D(3.0, 1.0, 0.0), "localization", 5.0))
    assert seen[0] == on_odometry
    assert math.isclose(seen[1].x_m, 1.0, abs_tol=1e-9) and math.isclose(seen[1].y_m, 1.0, abs_tol=1e-9)
    assert any("steering by localization now, not odometry" in message and "0.15 m" in message
               for _, message in events), events
