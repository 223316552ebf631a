"""What every skill controller shares: the inputs of a tick, the step it returns, and its outcome."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from skill_server.goals import EventKind, GoalFeedback, GoalStatus
from skill_server.sim.geometry import Pose2D, wrap_angle
from skill_server.sim.laser import LaserSpec
from skill_server.sim.odometry import OdometryReading
from skill_server.sim.robot_model import RobotSpec


@dataclass(frozen=True)
class SensorLayout:
    """Where the range sensors look, in the robot frame (skills need it to place readings)."""

    sonar_mount_rad: tuple[float, ...]
    sonar_mount_radius_m: float
    sonar_max_range_m: float
    laser: LaserSpec

    @cached_property
    def laser_angles_rad(self) -> np.ndarray:
        """Beam directions in the robot frame (computed once: every skill reads them every scan)."""
        angles = np.linspace(self.laser.angle_min_rad, self.laser.angle_max_rad, self.laser.beam_count)
        angles.flags.writeable = False
        return angles


@dataclass(frozen=True)
class TickInput:
    """What a skill may read in one control tick: odometry, range sensors and the believed pose.

    Ground truth is deliberately absent: skills control from what a real robot could know.
    """

    sim_time_s: float
    dt_s: float
    odometry: OdometryReading
    sonar_ranges_m: tuple[float, ...]
    laser_ranges_m: tuple[float, ...]
    new_scan: bool  # the range sensors were read anew since the previous tick
    pose: Pose2D  # localization estimate when localization runs, else odometry
    pose_source: str
    spec: RobotSpec
    sensors: SensorLayout
    obstacles: object = None  # the detect-obstacle skill's ObstacleMap (typed loosely to avoid an import cycle)
    battery_charge: float = 1.0  # 0..1 of full (the simulated battery)
    line_readings: tuple[float, ...] = ()  # the line sensor's cells, 0..1, left to right (none: no line to read)


@dataclass(frozen=True)
class Outcome:
    """How a goal ended."""

    status: GoalStatus
    error_code: str = ""
    message: str = ""
    reached: bool = False


@dataclass(frozen=True)
class SkillStep:
    """A controller's answer to one tick: wheel command (motor skills), feedback, events, maybe an end."""

    linear_mps: float = 0.0
    angular_radps: float = 0.0
    feedback: GoalFeedback | None = None
    events: tuple[tuple[EventKind, str], ...] = ()
    outcome: Outcome | None = None


SKILL_CLASSES = ("motor", "perceptive", "sensorimotor", "deliberative")


class SkillController:
    """Base of every skill: ticked by the world loop, never a thread; motor skills drive the wheels.

    The class attributes are the skill's traits, published in ListSkills so that clients need not guess them
    from names.
    """

    motor: bool = True  # drives the wheels: one motor goal at a time; False for perceptive skills
    # The 2003 paper's class (SKILL_CLASSES): motor skills act from a command alone, perceptive ones interpret the
    # sensors, sensorimotor ones choose actions from what they perceive, deliberative ones reason over time.
    skill_class: str = "motor"
    estimates_pose: bool = False  # ticked first; while it runs the others steer by perception.localizer's pose
    direct_drive: bool = False  # does what Drive commands do; consoles offer the drive pad instead of a panel
    uses_map: bool = False  # builds or reads the environment model: clearing the map ends it

    def __init__(self) -> None:
        self.last_feedback = GoalFeedback()
        self._events: list[tuple[EventKind, str]] = []

    def tick(self, tick: TickInput) -> SkillStep:
        """One control step; subclasses implement control()."""
        linear, angular, outcome, feedback = self.control(tick)
        self.last_feedback = feedback
        events, self._events = tuple(self._events), []
        return SkillStep(linear, angular, feedback, events, outcome)

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Returns (linear_mps, angular_radps, outcome or None, feedback)."""
        raise NotImplementedError

    def announce(self, kind: EventKind, message: str) -> None:
        """Queues an event for the sequencer to publish after this tick."""
        self._events.append((kind, message))

    def stop(self) -> None:
        """Called once when the goal ends for any reason (release what the skill holds)."""

    def position(self) -> str:
        """Where the goal stands, for the message of an end that comes from outside (a plan: "line 3")."""
        return ""


def succeeded(message: str) -> Outcome:
    """A SUCCEEDED outcome with the goal reached."""
    return Outcome(GoalStatus.SUCCEEDED, "", message, reached=True)


def aborted(code: str, message: str) -> Outcome:
    """An ABORTED outcome with an error code and a sentence."""
    return Outcome(GoalStatus.ABORTED, code, message)


def feedback_for(
    tick: TickInput,
    state: str,
    progress: float,
    distance_error_m: float = 0.0,
    heading_error_rad: float = 0.0,
    **values: float,
) -> GoalFeedback:
    """Feedback stamped with the tick's time and believed pose."""
    return GoalFeedback(
        sim_time_s=tick.sim_time_s,
        state=state,
        progress=min(1.0, max(0.0, progress)),
        distance_error_m=distance_error_m,
        heading_error_rad=heading_error_rad,
        pose=tick.pose,
        pose_source=tick.pose_source,
        values=tuple(sorted(values.items())),
    )


@dataclass
class HeadingController:
    """Turns in place to a heading with a proportional law, slowing near the target to avoid overshoot."""

    gain: float = 2.5
    max_angular_radps: float = 1.2
    min_angular_radps: float = 0.06  # below this the wheels barely move; keeps the last degree converging
    settle_ticks: int = field(default=0)

    def command(self, heading_error_rad: float) -> float:
        """Angular velocity [rad/s] for a heading error [rad]."""
        angular = self.gain * heading_error_rad
        if abs(angular) < self.min_angular_radps:
            angular = math.copysign(self.min_angular_radps, heading_error_rad)
        return max(-self.max_angular_radps, min(self.max_angular_radps, angular))


def heading_error(target_rad: float, pose: Pose2D) -> float:
    """Signed error [rad] from the pose's heading to target, in [-pi, pi)."""
    return wrap_angle(target_rad - pose.theta_rad)


def bearing_to(pose: Pose2D, x_m: float, y_m: float) -> float:
    """Direction [rad] from pose's position to (x_m, y_m), in the world frame."""
    return math.atan2(y_m - pose.y_m, x_m - pose.x_m)
