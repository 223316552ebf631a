"""The goal RPCs of telelab.v1.Robot: activate, cancel, get, list, watch; map and localization streams."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

import grpc

from protos.telelab.v1 import robot_pb2
from skill_server.errors import (
    InvalidParameter,
    MissingControllerToken,
    NoMap,
    NotController,
    ResourceBusy,
    UnknownGoal,
    UnknownSkill,
    WorldStopped,
)
from skill_server.goals import Goal, GoalStatus
from skill_server.service import goal_convert
from skill_server.service.common import SimTimePacer, abort, stream_rate

if TYPE_CHECKING:
    from skill_server.sequencer import Sequencer
    from skill_server.sim.world import World

WATCH_POLL_S = 0.25
DEFAULT_FEEDBACK_HZ, MAX_FEEDBACK_HZ = 10.0, 50.0
DEFAULT_LOCALIZATION_HZ, MAX_LOCALIZATION_HZ = 5.0, 20.0
MAX_STREAMED_PARTICLES = 2000

_STATUS_OF_ERROR: list[tuple[type[Exception], grpc.StatusCode]] = [
    (UnknownSkill, grpc.StatusCode.NOT_FOUND),
    (UnknownGoal, grpc.StatusCode.NOT_FOUND),
    (InvalidParameter, grpc.StatusCode.INVALID_ARGUMENT),
    (ResourceBusy, grpc.StatusCode.FAILED_PRECONDITION),
    (NoMap, grpc.StatusCode.FAILED_PRECONDITION),
    (MissingControllerToken, grpc.StatusCode.UNAUTHENTICATED),
    (NotController, grpc.StatusCode.PERMISSION_DENIED),
    (WorldStopped, grpc.StatusCode.UNAVAILABLE),
]


class GoalRpcs:
    """Mixed into RobotService; every request is checked and carried out by the Sequencer in the loop."""

    _world: World
    _sequencer: Sequencer

    def ActivateSkill(
        self, request: robot_pb2.ActivateSkillRequest, context: grpc.ServicerContext
    ) -> robot_pb2.ActivateSkillResponse:
        """Starts a skill as a goal, or refuses with a status code and a reason."""
        with _domain_errors(context):
            parameters = goal_convert.parameters_from_proto(request.parameters)
            self._sequencer.validate(request.skill, parameters)  # refuse bad input without waiting for the loop
            activation = self._world.run_in_loop(
                lambda: self._sequencer.activate(request.token, request.skill, parameters, request.preempt)
            )
        return robot_pb2.ActivateSkillResponse(
            goal=goal_convert.goal_to_proto(activation.goal), preempted_goal_id=activation.preempted_goal_id
        )

    def CancelGoal(self, request: robot_pb2.CancelGoalRequest, context: grpc.ServicerContext) -> robot_pb2.GoalState:
        """Cancels a goal; answers its state afterwards."""
        with _domain_errors(context):
            snapshot = self._world.run_in_loop(lambda: self._sequencer.cancel(request.token, request.goal_id))
        return goal_convert.goal_to_proto(snapshot)

    def GetGoal(self, request: robot_pb2.GetGoalRequest, context: grpc.ServicerContext) -> robot_pb2.GoalState:
        """The state of one goal."""
        return goal_convert.goal_to_proto(self._goal(request.goal_id, context).snapshot())

    def ListGoals(
        self, request: robot_pb2.ListGoalsRequest, context: grpc.ServicerContext
    ) -> robot_pb2.ListGoalsResponse:
        """Running goals and the ones kept after their end."""
        return robot_pb2.ListGoalsResponse(
            goals=[goal_convert.goal_to_proto(goal.snapshot()) for goal in self._sequencer.goals.all()]
        )

    def WatchGoal(
        self, request: robot_pb2.WatchGoalRequest, context: grpc.ServicerContext
    ) -> Iterator[robot_pb2.GoalUpdate]:
        """State, then events as they happen, every later state (executing, canceling, the final one) and
        feedback at the asked rate."""
        rate_hz = stream_rate(context, "feedback_rate_hz", request.feedback_rate_hz, DEFAULT_FEEDBACK_HZ,
                              MAX_FEEDBACK_HZ, "Hz")
        goal = self._goal(request.goal_id, context)
        book = self._sequencer.goals
        cancelled = threading.Event()

        def on_rpc_done() -> None:
            cancelled.set()
            book.wake()

        context.add_callback(on_rpc_done)
        pacer = SimTimePacer(1.0 / rate_hz)
        first = goal.snapshot()
        yield robot_pb2.GoalUpdate(state=goal_convert.goal_to_proto(first))
        events_sent, feedback_seen, status_sent = 0, first.feedback_version, first.status
        while context.is_active() and not cancelled.is_set() and not book.closed:
            for event in goal.events_since(events_sent):
                yield robot_pb2.GoalUpdate(event=goal_convert.event_to_proto(events_sent, event))
                events_sent += 1
            snapshot = goal.snapshot()
            if snapshot.event_count > events_sent:
                continue
            if snapshot.status != status_sent:
                # A watcher that began while the goal was only accepted must still see it start executing.
                status_sent = snapshot.status
                yield robot_pb2.GoalUpdate(state=goal_convert.goal_to_proto(snapshot))
            if snapshot.status.is_terminal:
                return
            if snapshot.feedback_version != feedback_seen:
                feedback_seen = snapshot.feedback_version
                if pacer.due(snapshot.feedback.sim_time_s):
                    yield robot_pb2.GoalUpdate(feedback=goal_convert.feedback_to_proto(snapshot.feedback))
            seen = feedback_seen

            def changed(goal: Goal = goal, seen: int = seen, sent: int = events_sent,
                        status: GoalStatus = status_sent) -> bool:
                return cancelled.is_set() or goal.feedback_version != seen or len(goal.events) > sent or (
                    goal.status != status)

            book.wait(WATCH_POLL_S, changed)

    def GetMap(self, request: robot_pb2.GetMapRequest, context: grpc.ServicerContext) -> robot_pb2.OccupancyGrid:
        """The latest environment model; FAILED_PRECONDITION before any mapping."""
        grid = self._sequencer.perception.published_map
        if grid is None:
            abort(context, grpc.StatusCode.FAILED_PRECONDITION,
                  "no environment model yet: activate environment_modelling and drive the robot around")
        return goal_convert.grid_to_proto(grid)

    def StreamLocalization(
        self, request: robot_pb2.StreamLocalizationRequest, context: grpc.ServicerContext
    ) -> Iterator[robot_pb2.LocalizationUpdate]:
        """Estimate, uncertainty, particles, odometry and ground truth at the asked rate of sim time."""
        rate_hz = stream_rate(context, "rate_hz", request.rate_hz, DEFAULT_LOCALIZATION_HZ, MAX_LOCALIZATION_HZ,
                              "Hz")
        particles = min(int(request.max_particles), MAX_STREAMED_PARTICLES)
        cancelled = threading.Event()

        def on_rpc_done() -> None:
            cancelled.set()
            self._world.wake_waiters()

        context.add_callback(on_rpc_done)
        pacer = SimTimePacer(1.0 / rate_hz)
        last_tick = -1
        while context.is_active() and not cancelled.is_set():
            snapshot = self._world.wait_for_snapshot(last_tick, WATCH_POLL_S, cancelled)
            if snapshot is None:
                if not self._world.is_running:
                    return
                continue
            last_tick = snapshot.tick
            if pacer.due(snapshot.sim_time_s):
                estimate = self._sequencer.perception.published_estimate
                yield goal_convert.localization_to_proto(snapshot, estimate, particles)

    def _goal(self, goal_id: str, context: grpc.ServicerContext) -> Goal:
        goal = self._sequencer.goals.get(goal_id)
        if goal is None:
            abort(context, grpc.StatusCode.NOT_FOUND, f"no goal {goal_id!r} (never issued, or finished too long ago)")
        return goal


class _domain_errors:  # noqa: N801 - used as a context manager, reads like a clause
    """Turns the robot core's errors into status codes with their sentence."""

    def __init__(self, context: grpc.ServicerContext) -> None:
        self._context = context

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, traceback: Any) -> bool:
        if error is None:
            return False
        for error_type, code in _STATUS_OF_ERROR:
            if isinstance(error, error_type):
                if isinstance(error, InvalidParameter):
                    self._context.set_trailing_metadata((("field", error.field),))
                abort(self._context, code, str(error))
        return False
