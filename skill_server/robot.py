"""The robot as its adapters see it: one facade over the world, the sequencer and the hand-off to the loop.

The gRPC servicer reaches the robot core only through `Robot`. Rules that span the world and the skills live
here, once: a direct Drive takes the wheels back from the running motor goal before it is acknowledged.
Streams are plain iterators of domain objects, paced in sim time, that end when the caller sets its `stopped`
event (and calls `wake_streams()`), when the world stops, or when what they follow ends.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, replace
from typing import TypeVar

from skill_server.errors import NoMap, NoTrack, NotRestartable, RobotError, UnknownGoal, WorldStopped
from skill_server.goals import Goal, GoalEvent, GoalFeedback, GoalSnapshot, GoalStatus
from skill_server.plans.model import (
    DriveLine,
    IfLine,
    InvalidPlan,
    OnLine,
    Plan,
    PlanCondition,
    PlanError,
    PlanLine,
    RepeatLine,
    SayLine,
    SetLine,
    SkillLine,
    WaitLine,
)
from skill_server.plans.validation import check_plan
from skill_server.process import ProcessFacts, ProcessWatch
from skill_server.sequencer import Activation, Sequencer, attach_sequencer
from skill_server.sim.battery import BatterySpec, BatteryState
from skill_server.sim.camera import DEFAULT_CAMERA_FPS, MAX_CAMERA_FPS
from skill_server.sim.drive_gate import DriveAck, MotionLimits
from skill_server.sim.geometry import Pose2D
from skill_server.sim.health import Fault, LoopReport
from skill_server.sim.laser import LaserSpec
from skill_server.sim.pacing import SimTimePacer
from skill_server.sim.panels import PanelSpec
from skill_server.sim.placement import check_placement
from skill_server.sim.robot_model import TELEBOT
from skill_server.sim.scene_description import SceneDescription
from skill_server.sim.scenes import FloorPatch
from skill_server.sim.snapshots import CameraFrame, RobotDescription, RobotSnapshot
from skill_server.sim.track_monitor import TrackEvent, TrackMonitor, TrackState
from skill_server.sim.world import World
from skill_server.skills.catalog import default_registry
from skill_server.skills.environment_model import PublishedGrid
from skill_server.skills.evidence_grid import EvidenceGrid, RangeSensors
from skill_server.skills.perception import LocalizationEstimate, NavigationPose
from skill_server.skills.registry import SkillEntry, SkillRegistry
from skill_server.skills.teleperception import EvidenceState, PerceptionScan, Teleperception

# The value types adapters convert come from here too, so that they import nothing from sim/ or skills/.
__all__ = [
    "DEFAULT_CAMERA_FPS", "MAX_CAMERA_FPS", "Activation", "BatterySpec", "BatteryState", "CameraFrame", "DriveAck",
    "DriveOrder", "DriveOutcome",
    "FloorPatch", "GoalUpdate", "LaserSpec", "LocalizationEstimate", "MotionLimits", "NavigationPose", "NumberedEvent",
    "PanelSpec", "Pose2D", "PublishedGrid", "Robot", "RobotDescription", "RobotSnapshot", "SceneDescription",
    "SkillEntry", "TrackEvent", "TrackState",
    # a plan's shapes, for RunPlan's conversion
    "DriveLine", "IfLine", "InvalidPlan", "OnLine", "Plan", "PlanCondition", "PlanError", "PlanLine", "RepeatLine",
    "SayLine", "SetLine", "SkillLine", "WaitLine",
]

__all__ += ["EvidenceState", "PerceptionScan"]  # teleperception

Published = TypeVar("Published", RobotSnapshot, CameraFrame)

POLL_S = 0.25  # how long a stream waits before re-checking that its caller still wants it


@dataclass(frozen=True)
class NumberedEvent:
    """A goal's event with its position in the goal's log."""

    index: int
    event: GoalEvent


GoalUpdate = GoalSnapshot | NumberedEvent | GoalFeedback


@dataclass(frozen=True)
class DriveOrder:
    """One drive command of a driver's stream, as it arrived (values checked by the drive gate)."""

    token: str
    sequence: int
    linear_mps: object
    angular_radps: object


@dataclass(frozen=True)
class DriveOutcome:
    """What one command of a driver's stream came to: the ack, or the refusal a unary Drive would have raised."""

    sequence: int
    ack: DriveAck | None
    refusal: RobotError | None



@dataclass(frozen=True)
class RobotHealth:
    """What a tutor diagnoses a robot by: its loop against real time, its faults, its process."""

    loop: LoopReport
    faults: list[Fault]
    process: ProcessFacts

class Robot:
    """One simulated robot: its description, commands, goals, maps and streams."""

    def __init__(self, world: World, sequencer: Sequencer, name: str = "lab-1") -> None:
        self.world = world
        self.sequencer = sequencer
        self.name = name
        self.teleperception = _teleperception_of(world)
        self.process = ProcessWatch()  # `python -m skill_server` hands in one that can restart it

    @classmethod
    def build(
        cls,
        scene: str = "lab",
        *,
        name: str = "lab-1",
        seed: int = 0,
        realtime: bool = True,
        deadman_timeout_s: float = 0.4,
        registry: SkillRegistry | None = None,
        battery: BatterySpec | None = None,
    ) -> Robot:
        """A robot in scene with every catalogued skill (or registry's), not started yet (battery: the Telebot's
        unless given, e.g. a tiny one for tests)."""
        spec = TELEBOT if battery is None else replace(TELEBOT, battery=battery)
        world = World(scene, seed=seed, realtime=realtime, deadman_timeout_s=deadman_timeout_s, spec=spec)
        return cls(world, attach_sequencer(world, registry or default_registry(world.spec)), name)

    # ---- lifecycle -------------------------------------------------------------------------------

    def start(self) -> None:
        """Starts the world's loop."""
        self.world.start()

    def stop(self) -> None:
        """Stops the loop and wakes every stream and goal watcher for good."""
        self.world.stop()
        self.sequencer.goals.close()

    @property
    def is_running(self) -> bool:
        """True while the world's loop runs."""
        return self.world.is_running

    # ---- description -----------------------------------------------------------------------------

    def describe(self) -> RobotDescription:
        """The robot's figures, sensors and scene."""
        return self.world.describe()

    def scene_description(self) -> SceneDescription:
        """The static world, the robot's body, its camera and sensors, as a view drawn elsewhere needs them."""
        return self.world.describe_scene()

    @property
    def scene_name(self) -> str:
        """The name of the scene the robot is in."""
        return self.world.scene.name

    def skills(self) -> list[SkillEntry]:
        """The skills offered with their schemas and traits, in the order panels should appear."""
        return self.sequencer.registry.entries()

    # ---- commands --------------------------------------------------------------------------------

    def set_controller(self, token: str) -> None:
        """Names the controller; an empty token revokes control and stops the base (the motor goal aborts)."""
        self.world.set_controller(token)

    def drive(self, token: str, sequence: int, linear_mps: object, angular_radps: object) -> DriveAck:
        """Sets the base's velocities for the controller; a direct drive preempts the running motor goal."""
        if self.sequencer.motor_goal_running:
            # Submitted in the loop between ticks: no tick sees the new target while the goal still drives,
            # and the goal has ended when the command is acknowledged.
            return self.world.run_in_loop(lambda: self._drive_over_motor_goal(token, sequence, linear_mps,
                                                                              angular_radps))
        ack = self.world.drive(token, sequence, linear_mps, angular_radps)
        if self.sequencer.motor_goal_running:  # a goal was activated while this command was on its way
            self.world.run_in_loop(self._take_wheels_back)
        return ack

    def drive_each(self, orders: Iterable[DriveOrder]) -> Iterator[DriveOutcome]:
        """One driver's commands, each applied as drive() applies it (the deadman alike) and answered in order as it
        comes: a refused command is answered with its refusal and the driver's stream goes on; a stopped world ends
        it (WorldStopped), since no later command could be taken either."""
        for order in orders:
            try:
                ack = self.drive(order.token, order.sequence, order.linear_mps, order.angular_radps)
            except WorldStopped:
                raise
            except RobotError as refused:
                yield DriveOutcome(order.sequence, None, refused)
            else:
                yield DriveOutcome(order.sequence, ack, None)

    def limits(self) -> MotionLimits:
        """The velocity ceilings and the deadman timeout in force, with the ranges SetLimits accepts."""
        return self.world.limits

    def set_limits(self, token: str, max_linear_mps: object, max_angular_radps: object,
                   watchdog_s: object) -> MotionLimits:
        """The controller's new limits (0 keeps a value); they bind Drive commands, skills and plans alike."""
        return self.world.set_limits(token, max_linear_mps, max_angular_radps, watchdog_s)

    def activate(self, token: str, skill: str, parameters: Mapping[str, object], preempt: bool) -> Activation:
        """Starts a skill as a goal, or raises (unknown skill, invalid parameter, no control, busy)."""
        self.sequencer.validate(skill, parameters)  # refuse bad input without waiting for the loop
        return self.world.run_in_loop(lambda: self.sequencer.activate(token, skill, parameters, preempt))

    def run_plan(self, token: str, plan: Plan, preempt: bool) -> Activation:
        """Starts a plan as one motor goal, or raises: InvalidPlan naming every fault (checked here, before the
        loop), then as activate (no control, wheels busy)."""
        checked = check_plan(plan, self.sequencer.registry, self.sequencer.spec)
        return self.world.run_in_loop(lambda: self.sequencer.run_plan(token, checked, preempt))

    def cancel(self, token: str, goal_id: str) -> GoalSnapshot:
        """Cancels a goal; its state afterwards."""
        return self.world.run_in_loop(lambda: self.sequencer.cancel(token, goal_id))

    def clear_map(self, token: str) -> list[str]:
        """Forgets the environment model (supervisory); the ids of the mapping and localization goals ended."""
        return self.world.run_in_loop(lambda: self.sequencer.clear_map(token))

    def check_supervisor(self, token: str) -> None:
        """NotController unless token is the controller's (the middleware acts for a supervisor with it)."""
        self.sequencer.check_supervisory_token(token)

    def health(self) -> RobotHealth:
        """The loop against real time over the last seconds, the faults kept (oldest first), and the process."""
        return RobotHealth(self.world.health.report(), self.world.health.faults(), self.process.facts())

    def restart(self, token: str) -> None:
        """Restarts the robot's process once this answer is sent (supervisory); NotRestartable when it lives inside
        another program."""
        self.check_supervisor(token)
        if not self.process.restart():
            raise NotRestartable(f"{self.name} runs inside another program: restart it there.")

    def return_to_dock(self, token: str) -> tuple[list[str], Pose2D]:
        """Carries the robot to its scene's spawn pose (supervisory): every goal ends, odometry restarts there.

        The ids of the goals that were running, and the dock.
        """
        dock = self.world.scene.spawn
        return self._carry_to(token, dock), dock

    def place(self, token: str, pose: Pose2D, kidnap: bool = False) -> list[str]:
        """Places the robot at pose (supervisory), refused with InvalidParameter unless its body fits there on the
        floor: every goal ends, odometry restarts there (kidnap: odometry goes on from where it believed it was).
        The ids of the goals that were running."""
        check_placement(self.world.scene, pose, self.world.spec.body_radius_m)
        return self._carry_to(token, pose, kidnap)

    def _carry_to(self, token: str, pose: Pose2D, kidnap: bool = False) -> list[str]:
        def carry() -> list[str]:
            self.sequencer.check_supervisory_token(token)
            ended = self.sequencer.running_goal_ids()
            self.world.set_pose(pose, kidnap=kidnap)
            return ended

        return self.world.run_in_loop(carry)

    def _drive_over_motor_goal(self, token: str, sequence: int, linear_mps: object,
                               angular_radps: object) -> DriveAck:
        ack = self.world.drive(token, sequence, linear_mps, angular_radps)
        self._take_wheels_back()
        return ack

    def _take_wheels_back(self) -> None:
        self.sequencer.preempt_motor_goal_for_drive(self.world.drive_version)

    # ---- goals and perception --------------------------------------------------------------------

    def goal(self, goal_id: str) -> GoalSnapshot:
        """The state of one goal, live or kept after its end."""
        return self._goal(goal_id).snapshot()

    def goals(self) -> list[GoalSnapshot]:
        """Running goals and the ones kept after their end, oldest first."""
        return [goal.snapshot() for goal in self.sequencer.goals.all()]

    def environment_map(self) -> PublishedGrid:
        """The latest environment model (a PublishedGrid); NoMap before any mapping."""
        grid = self.sequencer.perception.published_map
        if grid is None:
            raise NoMap("no environment model yet: activate environment_modelling and drive the robot around")
        return grid

    # ---- teleperception ---------------------------------------------------------------------------

    def evidence(self, sensors: tuple[str, ...], parts: tuple[str, ...],
                 watch: bool) -> tuple[EvidenceState, Pose2D]:
        """The evidence grid's chosen layers with its counts, and the odometry pose now; watch keeps it
        accumulating."""
        if watch:
            self.teleperception.watch()
        return self.teleperception.state(sensors, parts), self.world.snapshot.odometry.pose

    def reset_evidence(self, token: str) -> None:
        """Forgets the evidence grid and the readings kept (supervisory, like clear_map)."""

        def reset() -> None:
            self.sequencer.check_supervisory_token(token)
            self.teleperception.reset()

        self.world.run_in_loop(reset)

    def perception_scans(self, after_index: int) -> list[PerceptionScan]:
        """The raw readings kept, numbered above after_index, oldest first."""
        return self.teleperception.scans_after(after_index)

    def pose_log(self, from_unix_s: float, to_unix_s: float) -> tuple[list[tuple[float, ...]], float | None]:
        """The true and odometric poses kept between two wall-clock times, and the oldest time kept."""
        samples, oldest = self.world.pose_log.between(from_unix_s, to_unix_s)
        return list(samples), oldest

    def track_run(self) -> TrackState | None:
        """The run on the scene's track now; None in scenes without a track."""
        monitor = self.world.track_monitor
        return None if monitor is None else monitor.state()

    def restart_track_run(self) -> TrackState | None:
        """Ends the attempt under way without a result, so the next departure from A starts a new one; the run
        after that (None in scenes without a track)."""
        self.world.restart_track_run()
        return self.track_run()

    def _goal(self, goal_id: str) -> Goal:
        goal = self.sequencer.goals.get(goal_id)
        if goal is None:
            raise UnknownGoal(f"no goal {goal_id!r} (never issued, or finished too long ago)")
        return goal

    # ---- streams ---------------------------------------------------------------------------------

    def wake_streams(self) -> None:
        """Wakes every stream blocked in a wait, so one whose caller set its stopped event ends at once."""
        self.world.wake_waiters()
        self.sequencer.goals.wake()

    def telemetry(self, period_s: float, stopped: threading.Event) -> Iterator[RobotSnapshot]:
        """Snapshots, at most one per period_s of sim time."""
        pacer = SimTimePacer(period_s)
        for snapshot in self._snapshots(stopped):
            if pacer.due(snapshot.sim_time_s):
                yield snapshot

    def camera(self, max_fps: float, stopped: threading.Event) -> Iterator[CameraFrame]:
        """Frames, rendered only while someone watches (the loop renders for the fastest watcher)."""
        pacer = SimTimePacer(1.0 / max_fps)
        try:
            subscription = self.world.subscribe_camera(max_fps)
        except WorldStopped:
            return
        with subscription:
            for frame in self._published(self.world.wait_for_frame, lambda f: f.frame_sequence, stopped):
                if pacer.due(frame.sim_time_s):
                    yield frame

    def localization(
        self, period_s: float, stopped: threading.Event
    ) -> Iterator[tuple[RobotSnapshot, LocalizationEstimate | None, NavigationPose | None]]:
        """(snapshot, the localization estimate or None, the pose the skills steer by), at most one per period_s of
        sim time."""
        pacer = SimTimePacer(period_s)
        perception = self.sequencer.perception
        for snapshot in self._snapshots(stopped):
            if pacer.due(snapshot.sim_time_s):
                yield snapshot, perception.published_estimate, perception.navigation

    def goal_updates(self, goal_id: str, feedback_period_s: float, stopped: threading.Event) -> Iterator[GoalUpdate]:
        """The goal's state, then its events as they happen, every later state and feedback at most once per
        feedback_period_s of sim time, until the final state (UnknownGoal at once for an unknown id)."""
        goal = self._goal(goal_id)
        return self._goal_updates(goal, feedback_period_s, stopped)

    def track_events(self, after_index: int, stopped: threading.Event) -> Iterator[TrackEvent]:
        """Every track event numbered above after_index, as they happen (NoTrack at once off a track)."""
        monitor = self.world.track_monitor
        if monitor is None:
            raise NoTrack(f"the scene {self.scene_name} has no track")
        return self._track_events(monitor, after_index, stopped)

    def _snapshots(self, stopped: threading.Event) -> Iterator[RobotSnapshot]:
        return self._published(self.world.wait_for_snapshot, lambda snapshot: snapshot.tick, stopped)

    def _published(
        self,
        wait_for: Callable[[int, float, threading.Event], Published | None],
        number_of: Callable[[Published], int],
        stopped: threading.Event,
    ) -> Iterator[Published]:
        """Each newer item the loop publishes (snapshots, frames), until stopped or the world stops."""
        last = -1
        while not stopped.is_set():
            item = wait_for(last, POLL_S, stopped)
            if item is None:
                if not self.world.is_running:
                    return
                continue
            last = number_of(item)
            yield item

    def _goal_updates(self, goal: Goal, feedback_period_s: float, stopped: threading.Event) -> Iterator[GoalUpdate]:
        book = self.sequencer.goals
        pacer = SimTimePacer(feedback_period_s)
        first = goal.snapshot()
        yield first
        events_sent, feedback_seen, status_sent = 0, first.feedback_version, first.status
        while not stopped.is_set() and not book.closed:
            for event in goal.events_since(events_sent):
                yield NumberedEvent(events_sent, event)
                events_sent += 1
            snapshot = goal.snapshot()
            if snapshot.event_count > events_sent:
                continue
            if snapshot.status != status_sent:
                # A watcher that began while the goal was only accepted must still see it start executing.
                status_sent = snapshot.status
                yield snapshot
            if snapshot.status.is_terminal:
                return
            if snapshot.feedback_version != feedback_seen:
                feedback_seen = snapshot.feedback_version
                if pacer.due(snapshot.feedback.sim_time_s):
                    yield snapshot.feedback
            seen = feedback_seen

            def changed(goal: Goal = goal, seen: int = seen, sent: int = events_sent,
                        status: GoalStatus = status_sent) -> bool:
                return stopped.is_set() or goal.feedback_version != seen or len(goal.events) > sent or (
                    goal.status != status)

            book.wait(POLL_S, changed)

    def _track_events(
        self, monitor: TrackMonitor, after_index: int, stopped: threading.Event
    ) -> Iterator[TrackEvent]:
        seen = after_index
        while not stopped.is_set() and self.world.is_running:
            for event in monitor.events_after(seen, POLL_S):
                seen = event.index
                yield event


def _teleperception_of(world: World) -> Teleperception:
    """The robot's teleperception over its scene's floor, fed by every snapshot its loop publishes."""
    info = world.describe()
    sensors = RangeSensors(info.sonars, info.spec.body_radius_m, info.laser)
    teleperception = Teleperception(EvidenceGrid(world.scene.floor_half_x_m, world.scene.floor_half_y_m, sensors))
    world.observe_snapshots(teleperception.observe)
    return teleperception
