"""The World: one pybullet client, one loop thread that alone touches it, immutable snapshots out."""

from __future__ import annotations

import dataclasses
import math
import queue
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any, Protocol, TypeVar

import numpy as np
import pybullet
from pybullet_utils import bullet_client  # type: ignore[import-untyped]

from skill_server.errors import InvalidParameter, WorldStopped
from skill_server.sim import robot_model
from skill_server.sim.battery import Battery, BatteryState, at_dock
from skill_server.sim.camera import DEFAULT_CAMERA_FPS, Camera, CameraSpec
from skill_server.sim.drive_gate import DriveAck, DriveGate, MotionLimits
from skill_server.sim.floor_line import LineSensor, LineSensorSpec
from skill_server.sim.geometry import Pose2D, yaw_from_quaternion
from skill_server.sim.health import LoopHealth
from skill_server.sim.laser import Laser, LaserSpec
from skill_server.sim.odometry import WheelOdometry
from skill_server.sim.pacing import SimTimePacer
from skill_server.sim.panels import LINE_SENSOR, TELEBOT_PANELS
from skill_server.sim.pose_log import PoseLog
from skill_server.sim.publication import CameraSubscription, Publication
from skill_server.sim.raycast import StaticSceneCaster
from skill_server.sim.robot_model import TELEBOT, RobotSpec, ramp_toward, wheel_speeds_radps
from skill_server.sim.scene_description import SceneDescription, describe_scene
from skill_server.sim.scenes import build_scene, get_scene
from skill_server.sim.snapshots import CameraFrame, RobotDescription, RobotSnapshot
from skill_server.sim.sonar import SonarRing, SonarRingSpec
from skill_server.sim.track_monitor import TrackMonitor

T = TypeVar("T")


class Autonomy(Protocol):
    """What the loop calls every tick to let skills drive (the sequencer implements it)."""

    def on_tick(self, snapshot: RobotSnapshot, dt_s: float) -> tuple[float, float] | None: ...

    def on_controller_changed(self, version: int) -> None: ...

    def on_reset(self, reason: str, pose_known: bool = True) -> None: ...

    def at_rest(self) -> bool:
        """No goal runs: nothing but a command can make the robot move."""
        ...

# What a class of robots on one host costs is mostly physics and the loop's wakes: every wake of a loop among 30
# finds cold caches. Control at 40 Hz instead of 60 holds 30 driven, watched robots on 2 cores (5.5 % of a core
# each); 30 Hz was cheaper still, but its 15 Hz scans left the localization filter overconfident in heading (67 %
# of samples within 2 std, 90 % at 20 Hz). Physics stays at 240 Hz: at 120 Hz the wheels slip enough to double the
# odometry's error over a drive with turns. A new drive target is not left waiting for its tick (see
# _serve_commands_for).
PHYSICS_DT_S = 1.0 / 240.0
PHYSICS_STEPS_PER_TICK = 6  # control at 40 Hz
SENSOR_EVERY_TICKS = 2  # sonar and laser at 20 Hz
SOLVER_ITERATIONS = 50  # pybullet's default; 20 let the wheels slip twice as much
OBSTACLE_GROUP = 0x1
ROBOT_GROUP = 0x10  # range sensors cast with a mask that leaves the robot out, so it never sees itself
SENSOR_RAY_MASK = 0x0F
MAX_REALTIME_LAG_S = 0.25  # beyond this the loop stops trying to catch up with the wall clock
# A robot nobody commands or watches, standing still with no goal, parks: its loop stops stepping the physics and
# publishes fresh sensor readings at 4 Hz, sim time following the wall clock, until a command or a viewer wakes it.
PARK_AFTER_S = 1.0
PARKED_PERIOD_S = 0.25
# What a pixel of render_surfaces() shows.
SURFACE_BACKGROUND, SURFACE_FLOOR, SURFACE_MARK, SURFACE_SOLID, SURFACE_ROBOT = range(5)
REST_SPEED_MPS = 1e-3
REST_TURN_RADPS = 1e-2


class World:
    """A simulated robot in a scene, stepped at a fixed rate by its own thread or synchronously."""

    def __init__(
        self,
        scene: str = "lab",
        *,
        seed: int = 0,
        realtime: bool = True,
        deadman_timeout_s: float = 0.4,
        spec: RobotSpec = TELEBOT,
        sonar: SonarRingSpec | None = None,
        laser: LaserSpec | None = None,
        camera: CameraSpec | None = None,
    ) -> None:
        if not (
            isinstance(deadman_timeout_s, (int, float)) and math.isfinite(deadman_timeout_s) and deadman_timeout_s > 0
        ):
            raise InvalidParameter("deadman_timeout_s", "deadman_timeout_s must be a finite number above 0 s")
        self.scene = get_scene(scene)
        self.spec = spec
        self.realtime = realtime
        self.tick_dt_s = PHYSICS_DT_S * PHYSICS_STEPS_PER_TICK
        self._sonar = SonarRing(sonar or SonarRingSpec(mount_radius_m=spec.body_radius_m))
        self._laser = Laser(laser or LaserSpec())
        self._camera = Camera(camera or CameraSpec(), spec)
        self._gate = DriveGate(spec, float(deadman_timeout_s))
        self._line_sensor = LineSensor(self.scene.line)
        self._caster = StaticSceneCaster(self.scene)  # the scene is static: exact hits without pybullet's cost
        self.track_monitor = TrackMonitor(self.scene.track) if self.scene.track is not None else None
        self._commands: queue.SimpleQueue[tuple[Callable[[], Any], Future[Any]]] = queue.SimpleQueue()
        self._command_waiting = threading.Event()  # set when a command is queued, so the loop wakes early
        self._frame_sequence = 0
        self._frame_pacer = SimTimePacer(1.0)  # its period follows the fastest camera viewer
        self._tick = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._closed = False
        self._rest_since_s: float | None = None
        self.parked = False  # read by tests and benchmarks
        self._publication = Publication()
        self.pose_log = PoseLog()
        self.health = LoopHealth()  # what a tutor's diagnosis reads: the loop against real time, and faults
        self._snapshot_observers: list[Callable[[RobotSnapshot], None]] = []
        self._autonomy: Autonomy | None = None
        self._scene_description: SceneDescription | None = None
        # Built in the caller's thread before the loop exists; from start() on only the loop touches it.
        self._client: Any = bullet_client.BulletClient(connection_mode=pybullet.DIRECT)
        self._build(seed)

    # ---- lifecycle -------------------------------------------------------------------------------

    def start(self) -> None:
        """Starts the loop thread; from now on only that thread touches pybullet."""
        if self._closed:
            raise WorldStopped("the world was stopped")
        if self._thread is not None:
            return
        self._thread = threading.Thread(target=self._run, name=f"world-{self.scene.name}", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stops the loop, joins it, disconnects pybullet and wakes every waiting reader."""
        if self._closed:
            return
        self._closed = True
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        self._fail_pending_commands()
        self._client.disconnect()
        self._publication.close()

    @property
    def is_running(self) -> bool:
        """True while the loop thread is running."""
        return self._thread is not None and not self._closed

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()

    # ---- commands from other threads -------------------------------------------------------------

    def attach_autonomy(self, autonomy: Autonomy) -> None:
        """Lets skills drive: the loop ticks autonomy before moving the base (call before start())."""
        self._autonomy = autonomy

    def observe_snapshots(self, observer: Callable[[RobotSnapshot], None]) -> None:
        """Hands observer every snapshot the loop publishes from now on, in the loop (keep it cheap)."""
        self._snapshot_observers.append(observer)

    def run_in_loop(self, action: Callable[[], T]) -> T:
        """Runs action in the loop thread (or at once before start()) and returns its result or raises."""
        return self._call_in_loop(action)

    @property
    def deadman_timeout_s(self) -> float:
        """How long a moving direct drive lasts without a newer command (the watchdog; SetLimits changes it)."""
        return self._gate.limits.watchdog_s

    @property
    def limits(self) -> MotionLimits:
        """The velocity ceilings and the deadman timeout in force."""
        return self._gate.limits

    def set_limits(self, token: str, max_linear_mps: object, max_angular_radps: object,
                   watchdog_s: object) -> MotionLimits:
        """The controller changes the limits (0 keeps a value); they apply from the next tick to every motion."""
        limits = self._gate.set_limits(token, max_linear_mps, max_angular_radps, watchdog_s)
        self._command_waiting.set()
        return limits

    @property
    def drive_version(self) -> int:
        """Grows with every accepted Drive command and controller change."""
        return self._gate.latest().version

    @property
    def controller_token(self) -> str:
        """The token whose commands are obeyed ("" when nobody has control)."""
        return self._gate.controller_token

    def set_controller(self, token: str) -> None:
        """Names the only token whose drive commands are obeyed; "" revokes control and stops the base."""
        self._gate.set_controller(token)
        self._command_waiting.set()

    def drive(self, token: str, sequence: int, linear_mps: object, angular_radps: object) -> DriveAck:
        """Sets the base's target velocities if token, values and sequence allow (see DriveGate.submit)."""
        ack = self._gate.submit(token, sequence, linear_mps, angular_radps)
        self._command_waiting.set()  # a parked loop wakes at once
        return ack

    def reset(self, seed: int) -> None:
        """Rebuilds the scene and robot, with noise seeded anew; sim time restarts at 0."""
        self._call_in_loop(lambda: self._build(seed))

    def restart_track_run(self) -> bool:
        """Ends the track's attempt under way without a result (TrackMonitor.restart), in the loop's thread."""
        monitor = self.track_monitor
        return monitor is not None and self._call_in_loop(lambda: monitor.restart(self._sim_time_s))

    def set_pose(self, pose: Pose2D, kidnap: bool = False) -> None:
        """Places the robot at pose (for tests, exercises and the return to the dock); odometry restarts there, or
        with kidnap goes on from where it believed the robot was (the robot is not told it was carried)."""
        self._call_in_loop(lambda: self._place_robot(pose, kidnap))

    def step_for(self, duration_s: float) -> RobotSnapshot:
        """Advances the world by duration_s of sim time in the caller's thread (only before start())."""
        if self._thread is not None or self._closed:
            raise RuntimeError("step_for is only for a world whose loop was never started")
        for _ in range(max(1, round(duration_s / self.tick_dt_s))):
            self._tick_once()
        return self.snapshot

    def subscribe_camera(self, max_fps: float = DEFAULT_CAMERA_FPS) -> CameraSubscription:
        """Asks the loop to render; it renders at the highest fps any subscriber asked for (cap 30)."""
        subscription = self._publication.subscribe_camera(max_fps)
        self._command_waiting.set()  # a parked loop wakes to render
        return subscription

    @property
    def camera_subscriber_count(self) -> int:
        """How many viewers currently hold the camera on."""
        return self._publication.camera_subscriber_count

    # ---- readers (any thread) --------------------------------------------------------------------

    @property
    def snapshot(self) -> RobotSnapshot:
        """The latest published snapshot."""
        return self._publication.snapshot

    @property
    def latest_frame(self) -> CameraFrame | None:
        """The latest camera frame, if any was rendered."""
        return self._publication.frame

    def wait_for_snapshot(
        self, after_tick: int, timeout_s: float, cancelled: threading.Event | None = None
    ) -> RobotSnapshot | None:
        """The newest snapshot with a tick above after_tick; None on timeout, cancel or stop."""
        return self._publication.wait_for_snapshot(after_tick, timeout_s, cancelled)

    def wait_for_frame(
        self, after_sequence: int, timeout_s: float, cancelled: threading.Event | None = None
    ) -> CameraFrame | None:
        """The newest frame with a sequence above after_sequence; None on timeout, cancel or stop."""
        return self._publication.wait_for_frame(after_sequence, timeout_s, cancelled)

    def wake_waiters(self) -> None:
        """Wakes every reader blocked in wait_for_*, so a cancelled stream notices at once."""
        self._publication.wake_waiters()

    def describe(self) -> RobotDescription:
        """The robot's figures, sensors and scene."""
        return RobotDescription(
            scene_name=self.scene.name,
            spec=self.spec,
            deadman_timeout_s=self.deadman_timeout_s,
            camera=self._camera.spec,
            sonars=self._sonar.spec.geometries(),
            laser=self._laser.spec,
            scene_boxes=tuple(self.scene.scene_boxes()),
            panels=TELEBOT_PANELS + ((LINE_SENSOR,) if self.scene.line is not None else ()),
            line_sensor=self.line_sensor_spec,
        )

    @property
    def line_sensor_spec(self) -> LineSensorSpec | None:
        """The line sensor's cells, when the scene has a line to read."""
        return self._line_sensor.spec if self.scene.line is not None else None

    def describe_scene(self) -> SceneDescription:
        """The static world as the loop builds it and the camera renders it, versioned (computed once)."""
        if self._scene_description is None:
            self._scene_description = describe_scene(self.scene, self.spec, self._camera.spec, self._laser.spec,
                                                     self._sonar.spec)
        return self._scene_description

    # ---- the loop (only this part touches pybullet) -----------------------------------------------

    def _run(self) -> None:
        wall_origin_s = time.monotonic()
        sim_origin_s = self._sim_time_s
        while not self._stop.is_set():
            self._run_pending_commands()
            if self._sim_time_s < sim_origin_s:  # a reset restarted sim time
                wall_origin_s, sim_origin_s = time.monotonic(), self._sim_time_s
            self._tick_once()
            if not self.realtime:
                self.health.note_tick(time.monotonic(), self._sim_time_s, 0.0)
                time.sleep(0)  # let gRPC threads take the GIL between ticks
                continue
            if self._rested_long_enough():
                self.health.note_parked(True)
                self._stay_parked()
                wall_origin_s, sim_origin_s = time.monotonic(), self._sim_time_s
                continue
            now_s = time.monotonic()
            lag_s = now_s - (wall_origin_s + self._sim_time_s - sim_origin_s)
            self.health.note_tick(now_s, self._sim_time_s, lag_s)
            if lag_s < 0:
                self._serve_commands_for(-lag_s, tick_on_drive=-lag_s <= self.tick_dt_s)
            elif lag_s > MAX_REALTIME_LAG_S:
                self.health.fault("behind_real_time", f"The simulation fell {lag_s:.2f} s behind real time; it "
                                  "dropped the backlog and goes on from now.")
                wall_origin_s, sim_origin_s = time.monotonic(), self._sim_time_s

    def _rested_long_enough(self) -> bool:
        if not self._at_rest():
            self._rest_since_s = None
            return False
        if self._rest_since_s is None:
            self._rest_since_s = self._sim_time_s
        return self._sim_time_s - self._rest_since_s >= PARK_AFTER_S

    def _at_rest(self) -> bool:
        """Nothing but a command can change the world: no drive target or motion, no goal. A camera viewer does not
        wake it: what the camera sees stands still too (the parked loop sends its frame again)."""
        if (self._gate.latest().version != self._seen_target_version or self._deadman_armed
                or self._target_linear_mps or self._target_angular_radps or self._linear_mps or self._angular_radps
                or (self._autonomy is not None and not self._autonomy.at_rest())):
            return False
        linear, angular = self._client.getBaseVelocity(self._robot)
        return math.hypot(linear[0], linear[1]) < REST_SPEED_MPS and abs(angular[2]) < REST_TURN_RADPS

    def _stay_parked(self) -> None:
        """Publishes fresh sensor readings every PARKED_PERIOD_S without stepping the physics, sim time following
        the wall clock, and to a camera viewer at its rate the frame rendered once when parked (nothing it shows
        moves), until something can move the robot again: a drive wakes the loop at once, and so does any command
        the loop runs (a placed or docked robot is stepped again, so the track monitor and the sensors see it)."""
        self.parked = True
        last_wall_s = time.monotonic()
        publish_due_s = last_wall_s + PARKED_PERIOD_S  # on a grid: a late wake-up does not delay the next one
        frame: CameraFrame | None = None
        frame_due_s = last_wall_s
        try:
            while not self._stop.is_set():
                fps = self._publication.requested_camera_fps
                wake_s = min(publish_due_s, frame_due_s) if fps > 0 else publish_due_s
                if self._command_waiting.wait(max(0.0, wake_s - time.monotonic())):
                    self._command_waiting.clear()
                    if self._run_pending_commands():
                        self._rest_since_s = None
                        return
                now_s = time.monotonic()
                published_due = now_s >= publish_due_s
                while publish_due_s <= now_s:
                    publish_due_s += PARKED_PERIOD_S
                ticks = int((now_s - last_wall_s) / self.tick_dt_s)
                if ticks and published_due:
                    last_wall_s += ticks * self.tick_dt_s
                    self._sim_time_s += ticks * self.tick_dt_s
                    self._tick += ticks
                    ground_truth = self._ground_truth()
                    self._drain_battery(ticks * self.tick_dt_s, ground_truth, 0.0, 0.0)
                    self._sense(ground_truth)
                    self._publish_snapshot(ground_truth)
                if fps > 0 and now_s >= frame_due_s:
                    frame = self._frame_again(frame)
                    frame_due_s = max(frame_due_s + 1.0 / fps, now_s)
                if not self._at_rest():
                    self._rest_since_s = None
                    return
        finally:
            self.parked = False

    def _frame_again(self, frame: CameraFrame | None) -> CameraFrame:
        """The parked robot's frame published anew (rendered the first time)."""
        if frame is None:
            return self.render_frame()
        self._frame_sequence += 1
        again = dataclasses.replace(frame, frame_sequence=self._frame_sequence, capture_unix_s=time.time(),
                                    sim_time_s=self._sim_time_s)
        self._publication.publish_frame(again)
        return again

    def _serve_commands_for(self, duration_s: float, tick_on_drive: bool) -> None:
        """Waits until the next tick is due, running commands as they arrive rather than at the tick.

        A command (a skill activation, a cancel) is answered within a millisecond instead of waiting up
        to a control period. With tick_on_drive, a new drive target ends the wait: the next tick runs at once and
        sim time runs up to a tick further ahead of the wall clock, the wait after it being that much longer.
        """
        deadline_s = time.monotonic() + duration_s
        while not self._stop.is_set():
            remaining_s = deadline_s - time.monotonic()
            if remaining_s <= 0 or not self._command_waiting.wait(remaining_s):
                return
            self._command_waiting.clear()
            self._run_pending_commands()
            if tick_on_drive and self._gate.latest().version != self._seen_target_version:
                return

    def _call_in_loop(self, action: Callable[[], T]) -> T:
        if self._closed:
            raise WorldStopped("the world was stopped")
        if self._thread is None or threading.current_thread() is self._thread:
            return action()  # before start(), or an action already in the loop asking for another
        future: Future[T] = Future()
        self._commands.put((action, future))
        self._command_waiting.set()
        return future.result(timeout=10.0)

    def _run_pending_commands(self) -> bool:
        """Runs the commands queued for the loop; whether there was any."""
        ran = False
        while True:
            try:
                action, future = self._commands.get_nowait()
            except queue.Empty:
                return ran
            ran = True
            try:
                future.set_result(action())
            except Exception as error:  # handed to the caller, who re-raises it in its own thread
                future.set_exception(error)

    def _fail_pending_commands(self) -> None:
        while True:
            try:
                _, future = self._commands.get_nowait()
            except queue.Empty:
                return
            future.set_exception(WorldStopped("the world was stopped"))

    def _build(self, seed: int) -> None:
        client = self._client
        client.resetSimulation()
        client.setGravity(0.0, 0.0, -9.81)
        client.setPhysicsEngineParameter(fixedTimeStep=PHYSICS_DT_S, numSubSteps=0,
                                         numSolverIterations=SOLVER_ITERATIONS)
        self._scene_bodies = build_scene(client, self.scene, OBSTACLE_GROUP)
        spawn = self.scene.spawn
        self._robot = client.loadURDF(
            str(robot_model.URDF_PATH),
            [spawn.x_m, spawn.y_m, 0.0],
            client.getQuaternionFromEuler([0.0, 0.0, spawn.theta_rad]),
            flags=client.URDF_USE_INERTIA_FROM_FILE | client.URDF_USE_IMPLICIT_CYLINDER,
        )
        self._base_z_m = client.getBasePositionAndOrientation(self._robot)[0][2]
        for link in range(-1, client.getNumJoints(self._robot)):
            client.setCollisionFilterGroupMask(self._robot, link, ROBOT_GROUP, -1)
        for caster in (2, 3):  # casters slide: they carry weight but neither grip nor resist turning
            client.changeDynamics(self._robot, caster, lateralFriction=0.0, rollingFriction=0.0, spinningFriction=0.0)
        for wheel in (robot_model.LEFT_WHEEL_JOINT, robot_model.RIGHT_WHEEL_JOINT):
            client.changeDynamics(self._robot, wheel, lateralFriction=1.2)
        self._seed = seed
        self._odometry_rng = np.random.default_rng([seed, 1])
        self._sensor_rng = np.random.default_rng([seed, 2])
        self._line_rng = np.random.default_rng([seed, 3])  # its own: a line leaves the ranges' noise as it was
        self._sim_time_s = 0.0
        self._linear_mps = 0.0  # after the acceleration ramp
        self._angular_radps = 0.0
        self._target_linear_mps = 0.0
        self._target_angular_radps = 0.0
        self._applied_sequence = 0
        self._seen_target_version = self._gate.latest().version
        self._last_command_sim_s = 0.0
        self._deadman_armed = False
        self._deadman_stopped = False
        self._battery = Battery(self.spec.battery, self.spec.max_linear_mps / self.spec.wheel_radius_m)
        self._drain_battery(0.0, spawn, 0.0, 0.0)  # the first snapshot already says whether it charges
        self._frame_pacer.restart()
        self._odometry = WheelOdometry(self.spec, spawn, self._odometry_rng)
        self._apply_wheel_speeds()
        self._read_odometry()
        self._sense(self._ground_truth())
        self._publish_snapshot()
        if self._autonomy is not None:
            self._autonomy.on_reset("reset")

    def _place_robot(self, pose: Pose2D, kidnap: bool = False) -> None:
        believed = self._odometry.reading.pose
        client = self._client
        client.resetBasePositionAndOrientation(
            self._robot,
            [pose.x_m, pose.y_m, self._base_z_m],
            client.getQuaternionFromEuler([0.0, 0.0, pose.theta_rad]),
        )
        client.resetBaseVelocity(self._robot, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
        self._linear_mps = self._angular_radps = 0.0
        self._target_linear_mps = self._target_angular_radps = 0.0
        self._odometry = WheelOdometry(self.spec, believed if kidnap else pose, self._odometry_rng)
        self._read_odometry()
        self._sense(self._ground_truth())
        self._publish_snapshot()
        if self._autonomy is not None:
            self._autonomy.on_reset("moved to a new pose", pose_known=not kidnap)

    def _tick_once(self) -> None:
        self._follow_drive_target()
        if self._autonomy is not None:
            command = self._autonomy.on_tick(self._publication.snapshot, self.tick_dt_s)
            if command is not None:  # a motor skill holds the wheels; the deadman guards Drive commands only
                self._target_linear_mps, self._target_angular_radps = command
                self._deadman_armed = False
        # One place for every motion source (Drive, skills, plans): the ceilings in force, and an empty battery.
        self._target_linear_mps, self._target_angular_radps = self._gate.limits.clamp(
            self._target_linear_mps, self._target_angular_radps)
        if self._battery.state.empty:
            self._target_linear_mps = self._target_angular_radps = 0.0
            self._deadman_armed = False
        dt_s = self.tick_dt_s
        self._linear_mps = ramp_toward(
            self._linear_mps, self._target_linear_mps, self.spec.max_linear_accel_mps2 * dt_s
        )
        self._angular_radps = ramp_toward(
            self._angular_radps, self._target_angular_radps, self.spec.max_angular_accel_radps2 * dt_s
        )
        self._apply_wheel_speeds()
        for _ in range(PHYSICS_STEPS_PER_TICK):
            self._client.stepSimulation()
        self._sim_time_s += dt_s
        self._tick += 1
        self._read_odometry(dt_s)
        ground_truth = self._ground_truth()
        self._drain_battery(dt_s, ground_truth, *wheel_speeds_radps(self.spec, self._linear_mps, self._angular_radps))
        if self.track_monitor is not None and self.track_monitor.observe(ground_truth, self._sim_time_s):
            self._place_robot(self.scene.spawn)  # a border line touched: the run restarts at A
            ground_truth = self.scene.spawn
        if self._tick % SENSOR_EVERY_TICKS == 0:
            self._sense(ground_truth)
        self._publish_snapshot(ground_truth)
        self._maybe_render()

    def _drain_battery(self, dt_s: float, pose: Pose2D, left_radps: float, right_radps: float) -> BatteryState:
        dock = self.scene.spawn
        docked = at_dock(pose.x_m, pose.y_m, dock.x_m, dock.y_m, self.spec.battery.dock_radius_m)
        state = self._battery.advance(dt_s, left_radps, right_radps, docked)
        self._gate.note_battery(state.empty)
        return state

    def _follow_drive_target(self) -> None:
        target = self._gate.latest()
        if target.version != self._seen_target_version:
            self._seen_target_version = target.version
            if self._autonomy is not None and not target.from_command:
                # A direct Drive's effect on skills (it preempts the motor goal) is the Robot facade's rule.
                self._autonomy.on_controller_changed(target.version)
            self._target_linear_mps, self._target_angular_radps = target.linear_mps, target.angular_radps
            self._applied_sequence = target.sequence
            # A stop leaves nothing for the deadman to stop: arming it would report every key release as a fault.
            moving = target.linear_mps != 0.0 or target.angular_radps != 0.0
            self._deadman_armed = target.from_command and moving
            self._deadman_stopped = False
            self._last_command_sim_s = self._sim_time_s
        elif self._deadman_armed and self._sim_time_s - self._last_command_sim_s > self.deadman_timeout_s:
            self._target_linear_mps = self._target_angular_radps = 0.0
            self._deadman_armed = False
            self._deadman_stopped = True
            self._gate.stopped_by_deadman(target.version)
            self.health.fault("deadman", f"No drive command came for {self.deadman_timeout_s:g} s while the base "
                              "moved: the deadman stopped it.")

    def _apply_wheel_speeds(self) -> None:
        left_radps, right_radps = wheel_speeds_radps(self.spec, self._linear_mps, self._angular_radps)
        torque_nm = self.spec.wheel_max_torque_nm
        self._client.setJointMotorControlArray(
            self._robot,
            [robot_model.LEFT_WHEEL_JOINT, robot_model.RIGHT_WHEEL_JOINT],
            pybullet.VELOCITY_CONTROL,
            targetVelocities=[left_radps, right_radps],
            forces=[torque_nm, torque_nm],
        )

    def _read_odometry(self, dt_s: float = 0.0) -> None:
        states = self._client.getJointStates(self._robot, [robot_model.LEFT_WHEEL_JOINT, robot_model.RIGHT_WHEEL_JOINT])
        self._odometry.update(states[0][0], states[1][0], dt_s if dt_s > 0 else self.tick_dt_s)

    def _ground_truth(self) -> Pose2D:
        position, orientation = self._client.getBasePositionAndOrientation(self._robot)
        return Pose2D(position[0], position[1], yaw_from_quaternion(orientation))

    def _sense(self, pose: Pose2D) -> None:
        """Reads the range sensors and the line sensor at pose."""
        self._sonar_ranges_m, self._laser_ranges_m = self._measure_ranges(pose)
        self._line_readings = self._line_sensor.read(pose, self._line_rng)

    def _measure_ranges(self, pose: Pose2D) -> tuple[tuple[float, ...], tuple[float, ...]]:
        sonar_from, sonar_to = self._sonar.rays(pose)
        laser_from, laser_to = self._laser.rays(pose)
        fractions = self._caster.cast(np.vstack([sonar_from, laser_from]), np.vstack([sonar_to, laser_to]))
        sonar_count = self._sonar.ray_count
        sonar_m = self._sonar.ranges(fractions[:sonar_count], self._sensor_rng)
        laser_m = self._laser.ranges(fractions[sonar_count:], self._sensor_rng)
        return tuple(sonar_m.tolist()), tuple(laser_m.tolist())

    def cast_rays(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """Hit fractions (1.0 = no hit) of rays that ignore the robot itself; loop thread or tests only."""
        results = self._client.rayTestBatch(starts.tolist(), ends.tolist(), collisionFilterMask=SENSOR_RAY_MASK)
        return np.array([hit[2] if hit[0] >= 0 else 1.0 for hit in results])

    def _publish_snapshot(self, ground_truth: Pose2D | None = None) -> None:
        reading = self._odometry.reading
        snapshot = RobotSnapshot(
            tick=self._tick,
            sim_time_s=self._sim_time_s,
            capture_unix_s=time.time(),
            last_applied_sequence=self._applied_sequence,
            odometry=reading,
            ground_truth=ground_truth or self._ground_truth(),
            sonar_ranges_m=self._sonar_ranges_m,
            laser_ranges_m=self._laser_ranges_m,
            line_readings=self._line_readings,
            deadman_stopped=self._deadman_stopped,
            commanded_linear_mps=self._linear_mps,
            commanded_angular_radps=self._angular_radps,
            battery=self._battery.state,
        )
        self._publication.publish_snapshot(snapshot)
        self.pose_log.note(snapshot)
        for observer in self._snapshot_observers:
            observer(snapshot)

    def _maybe_render(self) -> None:
        fps = self._publication.requested_camera_fps
        if fps <= 0:
            self._frame_pacer.restart()
            return
        self._frame_pacer.period_s = 1.0 / fps
        if self._frame_pacer.due(self._sim_time_s):
            self.render_frame()

    def render_frame(self) -> CameraFrame:
        """Renders, encodes and publishes one frame now (loop thread, or tests before start())."""
        pose = self._odometry.reading.pose
        jpeg = self._camera.render_jpeg(self._client, self._ground_truth())
        self._frame_sequence += 1
        spec = self._camera.spec
        frame = CameraFrame(
            frame_sequence=self._frame_sequence,
            capture_unix_s=time.time(),
            sim_time_s=self._sim_time_s,
            last_applied_sequence=self._applied_sequence,
            pose_at_capture=pose,
            width_px=spec.width_px,
            height_px=spec.height_px,
            jpeg=jpeg,
        )
        self._publication.publish_frame(frame)
        return frame

    def render_rgba(self) -> np.ndarray:
        """The raw camera image (for tests and inspection before start())."""
        return self._camera.render_rgba(self._client, self._ground_truth())

    def render_surfaces(self) -> tuple[np.ndarray, np.ndarray]:
        """The raw camera image and, per pixel, what it shows: a SURFACE_* code (tests and tools, before start()).

        The codes follow the scene description: the floor, a mark painted on it, a solid (wall, obstacle), the robot.
        """
        rgba, body_ids = self._camera.render_rgba_and_body_ids(self._client, self._ground_truth())
        floor, *rest = self._scene_bodies
        solids = len(self.scene.boxes) + len(self.scene.cylinders)
        surface_of = {floor: SURFACE_FLOOR, self._robot: SURFACE_ROBOT}
        surface_of.update({body: SURFACE_SOLID for body in rest[:solids]})
        surface_of.update({body: SURFACE_MARK for body in rest[solids:]})
        lookup = np.full(max(surface_of) + 2, SURFACE_BACKGROUND, dtype=np.uint8)
        for body, surface in surface_of.items():
            lookup[body] = surface
        return rgba, lookup[np.where(body_ids >= 0, body_ids & 0xFFFFFF, len(lookup) - 1)]
