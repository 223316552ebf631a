"""Complex skills as sequences of simple ones (the sequencer's composition), and round_trip built so."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

from skill_server.goals import EventKind, GoalFeedback, GoalStatus
from skill_server.schema import ParameterSchema, ParameterType, SkillDescription
from skill_server.sim.geometry import Pose2D
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import Outcome, SkillController, TickInput, feedback_for, succeeded
from skill_server.skills.go_to_goal import COORD_LIMIT_M, GoToGoal
from skill_server.skills.orientation import OrientationControl
from skill_server.skills.scan_matching import compose, relative

ROUND_TRIP = "round_trip"

StepFactory = Callable[[Pose2D], SkillController]  # builds a step from the pose where the sequence started


class StepSequence(SkillController):
    """Runs simple skills one after the other on the same goal; the first failure ends the whole.

    Subclasses (a plan's blocks) change how steps are named in feedback, events and failures through the hooks
    below, and may start the next step in the tick the previous one ended (advance_at_once).
    """

    skill_class = "sensorimotor"  # chooses its wheel commands from what the sensors report

    def __init__(self, steps: list[tuple[str, StepFactory]]) -> None:
        super().__init__()
        self._steps = steps
        self._index = -1
        self._current: SkillController | None = None
        self._start_pose: Pose2D | None = None
        self._start_source = ""
        self._start_odometry: Pose2D | None = None

    @property
    def current_step(self) -> str:
        """The name of the step running now."""
        return self._steps[self._index][0] if 0 <= self._index < len(self._steps) else ""

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Ticks the current step; moves on when it succeeds."""
        if self._start_pose is None:
            self._start_pose, self._start_source, self._start_odometry = tick.pose, tick.pose_source, tick.odometry.pose
        elif tick.pose_source != self._start_source:
            self._place_start_again(tick)
        while True:
            if self._current is None:
                self._advance(tick)
            assert self._current is not None
            step = self._current.tick(tick)
            for kind, message in step.events:
                self.relay_event(kind, message)
            progress = (self._index + (step.feedback.progress if step.feedback else 0.0)) / len(self._steps)
            feedback = self.step_feedback(tick, step.feedback or GoalFeedback(), progress)
            if step.outcome is None:
                return step.linear_mps, step.angular_radps, None, feedback
            self._current.stop()
            self._current = None
            if step.outcome.status is not GoalStatus.SUCCEEDED:
                return 0.0, 0.0, self.step_failed(step.outcome), feedback
            if self._index + 1 >= len(self._steps):
                return 0.0, 0.0, self.all_done(step.outcome), feedback
            if not self.advance_at_once():
                return 0.0, 0.0, None, feedback

    def stop(self) -> None:
        """Releases the step running now (a goal ended mid-step)."""
        if self._current is not None:
            self._current.stop()
            self._current = None

    # ---- hooks -------------------------------------------------------------------------------------

    def relay_event(self, kind: EventKind, message: str) -> None:
        """Publishes a step's event as the sequence's own (the sequence announces its own arrival)."""
        if kind is not EventKind.GOAL_REACHED:
            self.announce(kind, f"{self.current_step}: {message}")

    def step_feedback(self, tick: TickInput, step: GoalFeedback, progress: float) -> GoalFeedback:
        """The sequence's feedback from its step's."""
        feedback = feedback_for(tick, f"{self.current_step}:{step.state}", progress, step.distance_error_m,
                                step.heading_error_rad, step_index=float(self._index), **dict(step.values))
        return replace(feedback, planned_path=step.planned_path)  # the path ahead of a go-to-goal step

    def step_failed(self, outcome: Outcome) -> Outcome:
        """How the sequence ends when a step did not succeed."""
        return Outcome(outcome.status, outcome.error_code, f"{self.current_step}: {outcome.message}")

    def all_done(self, last: Outcome) -> Outcome:
        """How the sequence ends after its last step succeeded."""
        self.announce(EventKind.GOAL_REACHED, f"back at the start: {last.message}")
        return succeeded(f"all {len(self._steps)} steps done; last: {last.message}")

    def step_started(self) -> None:
        """Announces the step that begins now (the first one also says where the sequence will come back to)."""
        message = f"step {self._index + 1}/{len(self._steps)}: {self.current_step}"
        if self._index == 0 and self._start_pose is not None:
            message += f", from {_place(self._start_pose)} by {self._start_source}"
        self.announce(EventKind.STEP_STARTED, message)

    def advance_at_once(self) -> bool:
        """Whether the next step starts in the tick the previous one ended (else the wheels get a stop tick)."""
        return False

    def _advance(self, tick: TickInput) -> None:
        assert self._start_pose is not None
        self._index += 1
        _, factory = self._steps[self._index]
        self.step_started()
        self._current = factory(self._start_pose)

    def _place_start_again(self, tick: TickInput) -> None:
        """Another pose took over the steering (localization converged, or tracking against the floor plan began
        or was lost): the start's coordinates were in the other one's frame, which can be off by all the drift
        gathered before the start. At the first tick of the new frame the start is placed in it by the odometry
        since the start, which adds only the drift of those moments. Steps built later go back there."""
        assert self._start_pose is not None and self._start_odometry is not None
        start = compose(tick.pose, relative(tick.odometry.pose, self._start_odometry))
        moved_m = math.hypot(start.x_m - self._start_pose.x_m, start.y_m - self._start_pose.y_m)
        self.announce(EventKind.STEP_STARTED, f"steering by {tick.pose_source} now, not {self._start_source}: the "
                                              f"start is placed again, {moved_m:.2f} m from before, at {_place(start)}")
        self._start_pose, self._start_source, self._start_odometry = start, tick.pose_source, tick.odometry.pose


def _place(pose: Pose2D) -> str:
    return f"({pose.x_m:.2f}, {pose.y_m:.2f}) m"


def round_trip_description(spec: RobotSpec) -> SkillDescription:
    """The schema of round_trip."""
    return SkillDescription(
        name=ROUND_TRIP,
        title="Round trip",
        help=(
            "Complex skill: go to a point (go-to-goal), come back to where the robot started (go-to-goal) and "
            "turn back to the start heading (orientation control)."
        ),
        parameters=(
            ParameterSchema("goal_x_m", ParameterType.DOUBLE, "m", -COORD_LIMIT_M, COORD_LIMIT_M, 1.0,
                            "Turning point x in the lab frame."),
            ParameterSchema("goal_y_m", ParameterType.DOUBLE, "m", -COORD_LIMIT_M, COORD_LIMIT_M, 0.0,
                            "Turning point y in the lab frame."),
            ParameterSchema("speed_mps", ParameterType.DOUBLE, "m/s", 0.05, spec.max_linear_mps, 0.3,
                            "Cruising speed."),
            ParameterSchema("max_error_m", ParameterType.DOUBLE, "m", 0.02, 1.0, 0.03,
                            "Position tolerance at the turning point and back at the start."),
            ParameterSchema("heading_tolerance_rad", ParameterType.DOUBLE, "rad", 0.005, 0.5, 0.02,
                            "Heading tolerance back at the start."),
            ParameterSchema("timeout_s", ParameterType.DOUBLE, "s", 1.0, 1800.0, 300.0,
                            "Abort with TIMEOUT after this much time per step."),
        ),
    )


def round_trip(goal_x_m: float, goal_y_m: float, speed_mps: float, max_error_m: float,
               heading_tolerance_rad: float, timeout_s: float) -> StepSequence:
    """Go-to-goal out, go-to-goal back, orientation control to the start heading."""
    return StepSequence([
        # Step names are read by people in the console's events ("step 2/3: back to the start").
        ("out to the goal", lambda start: GoToGoal(goal_x_m, goal_y_m, speed_mps, max_error_m, timeout_s)),
        ("back to the start", lambda start: GoToGoal(start.x_m, start.y_m, speed_mps, max_error_m, timeout_s)),
        ("turning to the start heading",
         lambda start: OrientationControl(start.theta_rad, heading_tolerance_rad, 1.0, min(timeout_s, 60.0))),
    ])

