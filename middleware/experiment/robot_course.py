"""The robot's course run over gRPC (GetCourseRun), through the robot's link and its deadline."""

from __future__ import annotations

from middleware.robots.link import RobotLink
from protos.telelab.v1 import robot_pb2


def course_run(link: RobotLink) -> robot_pb2.CourseRun:
    """The course run now; RobotUnavailable when the robot does not answer.

    Uses the link's call wrapper (deadline, error mapping); a `course_run()` method on RobotLink would be the
    tidier home once link.py's owner agrees.
    """
    return link._call(link._stub.GetCourseRun, robot_pb2.GetCourseRunRequest())  # noqa: SLF001
