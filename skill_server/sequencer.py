"""The sequencer: owns the wheels, runs goals' controllers on the world's tick, and keeps perception data."""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

from skill_server.errors import (
    InvalidParameter,
    MissingControllerToken,
    NoMap,
    NotController,
    ResourceBusy,
    UnknownGoal,
)
from skill_server.goals import EventKind, Goal, GoalBook, GoalSnapshot, GoalStatus
from skill_server.plans.executor import PlanObserver, PlanRunner
from skill_server.plans.steps import DriveWatchdog, WatchdogChange
from skill_server.plans.validation import CheckedPlan
from skill_server.sim.drive_gate import BATTERY_EMPTY_MESSAGE
from skill_server.sim.geometry import Pose2D
from skill_server.sim.robot_model import RobotSpec
from skill_server.sim.snapshots import RobotSnapshot
from skill_server.skills.base import SensorLayout, SkillController, TickInput
from skill_server.skills.catalog import default_registry
from skill_server.skills.events import EventManager
from skill_server.skills.obstacles import ObstacleMap
from skill_server.skills.perception import NavigationPose, Perception
from skill_server.skills.pose_tracking import POSE_SOURCE, PoseTracker
from skill_server.skills.registry import SkillRegistry
from skill_server.skills.scan_matching import compose, relative

PLAN_GOAL_PREFIX = "plan:"  # a plan's goal is named "plan:<name>"
# A believed pose that moves this much more than odometry did in one tick has jumped: a localization found the
# robot elsewhere (after a kidnapping), or a source that had lost track took over again.
BELIEF_JUMP_M, BELIEF_JUMP_RAD = 0.3, math.radians(20.0)
FEEDBACK_PERIOD_S = 0.1  # feedback reaches the goal records at 10 Hz of sim time; events go at once


@dataclass(frozen=True)
class Activation:
    """An accepted goal, and the goal it preempted if any."""

    goal: GoalSnapshot
    preempted_goal_id: str


# Aborts that are someone's decision, not the robot failing: the controller changed, the world was reset.
ROUTINE_ABORTS = ("CONTROL_REVOKED", "RESET")

class Sequencer:
    """Runs at most one motor goal and any number of perceptive goals (one per skill) on the world's tick.

    Every method runs in the world's loop thread (the gRPC adapter gets there through World.run_in_loop),
    so goals and controllers need no locks of their own; watchers read goal records under the book's lock.
    """

    def __init__(
        self,
        spec: RobotSpec,
        sensors: SensorLayout,
        registry: SkillRegistry,
        goals: GoalBook,
        controller_token: Callable[[], str],
        drive_version: Callable[[], int] = lambda: 0,
    ) -> None:
        self.spec = spec
        self.sensors = sensors
        self.registry = registry
        self.goals = goals
        self.perception = Perception()
        self.events = EventManager()  # every goal's events of this tick, for the plans that react to them
        self._controller_token = controller_token
        self._drive_version = drive_version
        self._motor_since_version = 0  # Drive commands and controller changes older than the motor goal pass
        self._motor: tuple[Goal, SkillController] | None = None
        self._perceptive: dict[str, tuple[Goal, SkillController]] = {}
        self._stop_wheels = False
        self._last_laser: tuple[float, ...] | None = None
        self._sim_time_s = 0.0
        self._last_feedback_s: dict[str, float] = {}
        self._tracker: PoseTracker | None = None  # built at the first tick once the floor plan is known
        self._tracker_built = False
        self._last_belief: tuple[Pose2D, Pose2D] | None = None  # the pose steered by and odometry, last tick
        self.plan_observer: PlanObserver | None = None  # told when each plan's skill line starts (benchmarks)
        self.drive_watchdog: DriveWatchdog | None = None  # what a plan's `set watchdog` sets (attach_sequencer)
        self.on_fault: Callable[[str, str], None] | None = None  # told of each goal aborted (the robot's health)

    # ---- requests (loop thread) ------------------------------------------------------------------

    def validate(self, skill: str, parameters: Mapping[str, object]) -> dict[str, Any]:
        """The parameters checked against the skill's schema (any thread; raises on the first bad one)."""
        return self.registry.entry(skill).description.validate(parameters)

    def activate(self, token: str, skill: str, parameters: Mapping[str, object], preempt: bool) -> Activation:
        """Starts a goal, or raises (unknown skill, invalid parameter, no control, busy)."""
        entry = self.registry.entry(skill)
        values = entry.description.validate(parameters)
        self._check_token(token)
        holder = self._free_or_preempting(skill, entry.motor, preempt)
        return self._start(skill, entry.motor, values, entry.build(values, self.perception), holder,
                           entry.description.title)

    def run_plan(self, token: str, plan: CheckedPlan, preempt: bool) -> Activation:
        """Starts a checked plan as one motor goal "plan:<name>", or raises (no control, wheels busy)."""
        self._check_token(token)
        skill = f"{PLAN_GOAL_PREFIX}{plan.plan.name}"
        holder = self._free_or_preempting(skill, True, preempt)
        runner = PlanRunner(plan, self.registry, self.perception, self.spec, self.plan_observer, self.drive_watchdog,
                            self.events)
        return self._start(skill, True, {"steps": plan.expanded_steps}, runner, holder, f"Plan {plan.plan.name}")

    def _free_or_preempting(self, skill: str, motor: bool, preempt: bool) -> tuple[Goal, SkillController] | None:
        """The goal holding what skill needs, to be preempted; ResourceBusy when it holds it without preempt."""
        holder = self._motor if motor else self._perceptive.get(skill)
        if holder is not None and not preempt:
            goal = holder[0]
            what = "the wheels" if motor else f"the {skill} skill"
            raise ResourceBusy(f"{what} are held by {goal.goal_id} ({goal.skill}); activate with preempt to "
                               "cancel it, or cancel it first", goal.goal_id)
        return holder

    def _start(self, skill: str, motor: bool, values: dict[str, Any], controller: SkillController,
               holder: tuple[Goal, SkillController] | None, title: str) -> Activation:
        preempted = ""
        goal = self.goals.create(skill, motor, values, self._sim_time_s)
        if holder is not None:
            preempted = holder[0].goal_id
            self._end(holder, GoalStatus.CANCELED, "PREEMPTED", f"preempted by {goal.goal_id} ({skill})",
                      EventKind.PREEMPTED)
        if motor:
            self._motor = (goal, controller)
            self._motor_since_version = self._drive_version()
        else:
            self._perceptive[skill] = (goal, controller)
        goal.announce(self._sim_time_s, EventKind.STARTED, f"{title} started")
        return Activation(goal.snapshot(), preempted)

    def cancel(self, token: str, goal_id: str) -> GoalSnapshot:
        """Cancels a live goal (CANCELED, reporting the error left); a finished goal is returned as it is."""
        goal = self.goals.get(goal_id)
        if goal is None:
            raise UnknownGoal(f"no goal {goal_id!r} (never issued, or finished too long ago)")
        if goal.status.is_terminal:
            return goal.snapshot()
        self._check_token(token)
        running = self._running(goal_id)
        if running is not None:
            self._end(running, GoalStatus.CANCELED, "CANCELED", "canceled by the controller", EventKind.CANCELED)
        return goal.snapshot()

    def clear_map(self, token: str) -> list[str]:
        """Forgets the environment model; the goals built on it (mapping, localization) end as CANCELED. Their ids.

        Supervisory: token is the controller's, or empty while nobody has control (see check_supervisory_token).
        """
        self.check_supervisory_token(token)
        ended = []
        for running in [held for held in self._perceptive.values() if held[1].uses_map]:
            self._end(running, GoalStatus.CANCELED, "MAP_CLEARED", "the map was cleared", EventKind.CANCELED)
            ended.append(running[0].goal_id)
        perception = self.perception
        perception.environment, perception.published_map = None, None
        perception.localizer, perception.published_estimate = None, None
        return ended

    # ---- hooks the world calls (loop thread) -------------------------------------------------------

    @property
    def motor_goal_running(self) -> bool:
        """Whether a motor goal holds the wheels (read from other threads as a hint only)."""
        return self._motor is not None

    def at_rest(self) -> bool:
        """No goal runs and no stop is owed to the wheels (the world may park its loop)."""
        return self._motor is None and not self._perceptive and not self._stop_wheels

    def preempt_motor_goal_for_drive(self, version: int) -> None:
        """Ends the motor goal as PREEMPTED if it began before drive target version (the Robot facade decides when)."""
        if self._motor is not None and version > self._motor_since_version:
            self._end(self._motor, GoalStatus.CANCELED, "PREEMPTED", "preempted by a direct Drive command",
                      EventKind.PREEMPTED)
            self._stop_wheels = False  # the Drive that preempted the goal owns the wheels now: no stop over it

    def on_controller_changed(self, version: int) -> None:
        """Control changed hands or was revoked: the motor goal ends, the perceptive ones go on."""
        if self._motor is not None and version > self._motor_since_version:
            self._end(self._motor, GoalStatus.ABORTED, "CONTROL_REVOKED", "the controller changed; the base stops",
                      EventKind.FAILED)

    def on_reset(self, reason: str, pose_known: bool = True) -> None:
        """The world was reset or the robot moved by hand: every goal ends, the obstacle grid is redrawn. A robot
        carried off without being told (pose_known False, a kidnapping) leaves the pose tracking lost."""
        for running in [*([self._motor] if self._motor else []), *self._perceptive.values()]:
            self._end(running, GoalStatus.ABORTED, "RESET", f"the world was {reason}", EventKind.FAILED)
        self.perception.obstacles = ObstacleMap()
        self._last_belief = None
        if self._tracker is not None and pose_known:
            self._tracker.restart()  # the robot was placed: its pose is known again
        elif self._tracker is not None:
            self._tracker.lose()
        self._last_laser = None
        self._stop_wheels = False

    def on_tick(self, snapshot: RobotSnapshot, dt_s: float) -> tuple[float, float] | None:
        """Ticks every running controller; returns the wheel command, or None to leave the wheels alone."""
        self._sim_time_s = snapshot.sim_time_s
        self.events.new_tick(snapshot.sim_time_s)
        new_scan = snapshot.laser_ranges_m is not self._last_laser
        self._last_laser = snapshot.laser_ranges_m
        tick = TickInput(
            sim_time_s=snapshot.sim_time_s,
            dt_s=dt_s,
            odometry=snapshot.odometry,
            sonar_ranges_m=snapshot.sonar_ranges_m,
            laser_ranges_m=snapshot.laser_ranges_m,
            new_scan=new_scan,
            pose=snapshot.odometry.pose,
            pose_source="odometry",
            spec=self.spec,
            sensors=self.sensors,
            obstacles=self.perception.obstacles,
            battery_charge=snapshot.battery.charge,
            line_readings=snapshot.line_readings,
        )
        # Pose estimators first, so the others (and the obstacle grid) use the pose they believe.
        tracker = self._pose_tracker()
        if tracker is not None:
            tracker.update(tick, defer_search=self.perception.localizer is not None)
        perceptive = list(self._perceptive.values())
        for running in perceptive:
            if running[1].estimates_pose:
                self._step(running, tick)
        tick = self._with_believed_pose(tick)
        if tracker is not None and tick.pose_source == "localization" \
                and tracker.believed_pose(tick.odometry.pose) is None:
            tracker.adopt(tick.pose, tick.odometry.pose)  # lost, while the localization skill knows the place
        self.perception.navigation = NavigationPose(tick.pose, tick.pose_source)
        if self._belief_jumped(tick):
            # The obstacle grid's echoes were placed at the poses believed before the jump, wrong by the jump: after
            # a kidnapping, the scans of the search drawn where odometry believed the robot was walled go_to_goal in
            # (UNREACHABLE). They are dropped; the laser draws the grid again from the pose found.
            self.perception.obstacles.forget()
        for running in perceptive:
            if not running[1].estimates_pose:
                self._step(running, tick)
        if new_scan:
            self.perception.obstacles.add_scan(tick)
        if self._motor is not None and snapshot.battery.empty:
            self._end(self._motor, GoalStatus.ABORTED, "BATTERY_EMPTY", BATTERY_EMPTY_MESSAGE, EventKind.FAILED)
        if self._motor is not None:
            command = self._step(self._motor, tick)
            if command is not None:
                return command
        if self._stop_wheels:
            self._stop_wheels = False
            return 0.0, 0.0
        return None

    # ---- internals ---------------------------------------------------------------------------------

    def start_pose_tracking(self) -> None:
        """Builds the pose tracking against the floor plan now (else at the first tick)."""
        self._pose_tracker()

    def _pose_tracker(self) -> PoseTracker | None:
        if not self._tracker_built and self.perception.floor_plan is not None:
            self._tracker_built = True
            try:
                self._tracker = PoseTracker(self.perception.floor_plan)
            except NoMap:
                self._tracker = None  # a floor plan with nothing to see: odometry it is
        return self._tracker

    def _belief_jumped(self, tick: TickInput) -> bool:
        """Whether the pose the skills steer by moved BELIEF_JUMP further than odometry since the last tick."""
        last, self._last_belief = self._last_belief, (tick.pose, tick.odometry.pose)
        if last is None:
            return False
        expected = compose(last[0], relative(last[1], tick.odometry.pose))
        turn = abs(math.remainder(tick.pose.theta_rad - expected.theta_rad, 2 * math.pi))
        return tick.pose.distance_to(expected) > BELIEF_JUMP_M or turn > BELIEF_JUMP_RAD

    def _with_believed_pose(self, tick: TickInput) -> TickInput:
        """The best pose the robot has: the localization skill's (a person runs it), else the navigation stack's
        own tracking against the floor plan, else odometry."""
        localizer = self.perception.localizer
        pose = None if localizer is None else localizer.believed_pose(tick.odometry.pose)
        if pose is not None:
            return replace(tick, pose=pose, pose_source="localization")
        pose = None if self._tracker is None else self._tracker.believed_pose(tick.odometry.pose)
        if pose is not None:
            return replace(tick, pose=pose, pose_source=POSE_SOURCE)
        return tick

    def _step(self, running: tuple[Goal, SkillController], tick: TickInput) -> tuple[float, float] | None:
        goal, controller = running
        if goal.status is GoalStatus.ACCEPTED:
            goal.set_status(GoalStatus.EXECUTING)
        step = controller.tick(tick)
        for kind, message in step.events:
            goal.announce(tick.sim_time_s, kind, message)
            self.events.publish(goal.skill, kind, message)
        if step.feedback is not None and (
            step.outcome is not None
            or tick.sim_time_s - self._last_feedback_s.get(goal.goal_id, -math.inf) >= FEEDBACK_PERIOD_S - 1e-9
        ):
            self._last_feedback_s[goal.goal_id] = tick.sim_time_s
            goal.report(step.feedback)
        if step.outcome is not None:
            outcome = step.outcome
            announced = EventKind.FAILED if outcome.status is GoalStatus.ABORTED else None
            self._end(running, outcome.status, outcome.error_code, outcome.message, announced, outcome.reached)
            return (0.0, 0.0) if goal.motor else None
        if not goal.motor:
            return None
        linear = max(-self.spec.max_linear_mps, min(self.spec.max_linear_mps, step.linear_mps))
        angular = max(-self.spec.max_angular_radps, min(self.spec.max_angular_radps, step.angular_radps))
        return linear, angular

    def _end(
        self,
        running: tuple[Goal, SkillController],
        status: GoalStatus,
        code: str,
        message: str,
        kind: EventKind | None,
        reached: bool = False,
    ) -> None:
        goal, controller = running
        feedback = controller.last_feedback
        where = controller.position()
        if where and not message.startswith(f"{where}: "):
            message = f"{where}: {message}"
        if status is not GoalStatus.SUCCEEDED and feedback.sim_time_s > 0:
            # The paper's rule: deactivating reports the error left between the robot and the goal.
            message += (f"; error left {feedback.distance_error_m:.3f} m, "
                        f"{math.degrees(feedback.heading_error_rad):.1f} deg")
        if kind is not None:
            goal.announce(self._sim_time_s, kind, message)
        if status is GoalStatus.ABORTED and code not in ROUTINE_ABORTS and self.on_fault is not None:
            self.on_fault("skill_aborted", f"{goal.skill} ({goal.goal_id}) aborted, {code}: {message}")
        goal.finish(status, self._sim_time_s, code, message, reached)
        controller.stop()
        self._last_feedback_s.pop(goal.goal_id, None)
        if self._motor is running:
            self._motor = None
            self._stop_wheels = True
        else:
            for skill, other in list(self._perceptive.items()):
                if other is running:
                    del self._perceptive[skill]

    def _running(self, goal_id: str) -> tuple[Goal, SkillController] | None:
        if self._motor is not None and self._motor[0].goal_id == goal_id:
            return self._motor
        return next((r for r in self._perceptive.values() if r[0].goal_id == goal_id), None)

    def running_goal_ids(self) -> list[str]:
        """The ids of the goals running now, the motor goal first."""
        return [goal.goal_id for goal, _ in [*([self._motor] if self._motor else []), *self._perceptive.values()]]

    def check_supervisory_token(self, token: str) -> None:
        """Supervisory actions (clearing the map, the return to the dock) take the controller's token, so they
        cannot cut into a turn they were not asked in, or an empty one while nobody has control: the
        middleware, which decides who may supervise, then acts for a tutor without taking anyone's turn."""
        if token != self._controller_token():
            raise NotController("this request's token is not the robot's current controller's")

    def _check_token(self, token: str) -> None:
        if not token:
            raise MissingControllerToken("activating or cancelling a skill needs the controller token")
        if token != self._controller_token():
            raise NotController("this request's controller token is not the robot's current controller")


class WorldWatchdog:
    """The world's drive watchdog as a plan sets it: through the world's SetLimits path, under the token of the
    controller the plan runs for, so the value is the one GetLimits reports and a new controller resets it."""

    def __init__(self, world: Any) -> None:
        self._world = world

    def change(self, watchdog_s: float, previous: WatchdogChange | None) -> WatchdogChange | None:
        """Sets the watchdog (the plan was checked: watchdog_s is in range); None when nobody has control."""
        token = self._world.controller_token
        if not token or (previous is not None and previous.token != token):
            return None
        replaced_s = self._world.limits.watchdog_s if previous is None else previous.previous_s
        try:
            self._world.set_limits(token, 0.0, 0.0, watchdog_s)
        except (InvalidParameter, MissingControllerToken, NotController):
            return None
        return WatchdogChange(token, replaced_s, watchdog_s)

    def restore(self, change: WatchdogChange) -> None:
        """Gives back the replaced value if the plan's controller still holds the robot and nobody changed it since
        (a new controller starts from the robot's own settings anyway)."""
        if self._world.controller_token != change.token or self._world.limits.watchdog_s != change.set_s:
            return
        with contextlib.suppress(InvalidParameter, MissingControllerToken, NotController):  # the controller changed
            self._world.set_limits(change.token, 0.0, 0.0, change.previous_s)  # in between: its own settings hold


def attach_sequencer(world: Any, registry: SkillRegistry | None = None, goals: GoalBook | None = None) -> Sequencer:
    """Builds a sequencer for a world's robot and sensors and lets the world's loop tick it."""
    info = world.describe()
    sensors = SensorLayout(
        sonar_mount_rad=tuple(s.mount_angle_rad for s in info.sonars),
        sonar_mount_radius_m=info.spec.body_radius_m,
        sonar_max_range_m=max((s.max_range_m for s in info.sonars), default=0.0),
        laser=info.laser,
    )
    sequencer = Sequencer(info.spec, sensors, registry or default_registry(info.spec), goals or GoalBook(),
                          lambda: world.controller_token, lambda: world.drive_version)
    sequencer.perception.floor_plan = getattr(world, "scene", None)
    sequencer.drive_watchdog = WorldWatchdog(world)
    health = getattr(world, "health", None)
    sequencer.on_fault = health.fault if health is not None else None
    sequencer.start_pose_tracking()  # before the loop runs: building it takes about 40 ms
    world.attach_autonomy(sequencer)
    return sequencer
