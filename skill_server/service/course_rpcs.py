"""The course RPCs of telelab.v1.Robot: the run now, and its events as they happen (course scenes only)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import grpc

from protos.telelab.v1 import robot_pb2

if TYPE_CHECKING:
    from skill_server.sim.world import World

EVENT_POLL_S = 0.25


class CourseRpcs:
    """Mixin of RobotService: reads the world's CourseMonitor (which the world loop ticks)."""

    _world: World

    def GetCourseRun(self, request: robot_pb2.GetCourseRunRequest,
                     context: grpc.ServicerContext) -> robot_pb2.CourseRun:
        """The course run now; is_course is false in scenes without a course."""
        monitor = self._world.course_monitor
        if monitor is None:
            return robot_pb2.CourseRun(is_course=False, scene_name=self._world.scene.name)
        state = monitor.state()
        return robot_pb2.CourseRun(
            is_course=True, scene_name=self._world.scene.name, phase=state.phase, attempt=state.attempt,
            elapsed_s=state.elapsed_s, errors=state.errors, last_attempt=state.last_attempt,
            last_total_time_s=state.last_total_time_s, last_errors=state.last_errors,
            last_finished_unix_s=state.last_finished_unix_s, started_unix_s=state.started_unix_s,
            last_started_unix_s=state.last_started_unix_s,
        )

    def StreamCourseEvents(self, request: robot_pb2.StreamCourseEventsRequest,
                           context: grpc.ServicerContext) -> Iterator[robot_pb2.CourseEvent]:
        """Every course event after request.after_index, until the client goes (FAILED_PRECONDITION off course)."""
        monitor = self._world.course_monitor
        if monitor is None:
            context.abort(grpc.StatusCode.FAILED_PRECONDITION, f"the scene {self._world.scene.name} has no course")
        seen = int(request.after_index)
        while context.is_active() and self._world.is_running:
            for event in monitor.events_after(seen, EVENT_POLL_S):
                seen = event.index
                yield robot_pb2.CourseEvent(
                    index=event.index, kind=event.kind, sim_time_s=event.sim_time_s, unix_s=event.unix_s,
                    attempt=event.attempt, elapsed_s=event.elapsed_s, errors=event.errors, message=event.message)
