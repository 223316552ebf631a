"""Every SQLAlchemy model, imported here so Alembic's env.py sees the whole metadata."""

from __future__ import annotations

from middleware.models.access import PoolQueueEntry, QueueEntry, RobotControl
from middleware.models.accounts import Role, User
from middleware.models.analytics import LearningEvent, QueueWait, RobotOutage, XapiStatement  # noqa: F401
from middleware.models.assessment import Attempt, AttemptReview, Exam, Question, SurveyResponse  # noqa: F401
from middleware.models.auth import LoginSession
from middleware.models.base import Base
from middleware.models.bookings import Booking
from middleware.models.chat import ChatMessage
from middleware.models.class_wall import ClassHand, ClassNotice, ClassTakeover  # noqa: F401
from middleware.models.courses import Course, CourseMembership, Invitation, LoginFailure
from middleware.models.exercises import Exercise, ExerciseAssignment, ExerciseCode, ExerciseRun  # noqa: F401
from middleware.models.experiment import ExperimentProtocol, Participant, Trial, VideoDelay  # noqa: F401
from middleware.models.farm import ClassSeat, ClassSession, PersonalRobotRecord  # noqa: F401
from middleware.models.lab import ResponseTimeReport  # noqa: F401
from middleware.models.lti import LtiContext, LtiGradePassback, LtiIdentity, LtiPlatform  # noqa: F401
from middleware.models.plans import PlanVersion, StoredPlan
from middleware.models.preferences import UserPreference
from middleware.models.recordings import RecordedCommand, Recording  # noqa: F401
from middleware.models.robots import Robot, RobotKindSetting
from middleware.models.teaching import GuidedSession, GuidedSessionPresence, Lesson, Tour  # noqa: F401

__all__ = [
    "Base", "Booking", "ChatMessage", "Course", "CourseMembership", "Invitation", "LoginFailure",
    "LoginSession", "PlanVersion", "PoolQueueEntry", "QueueEntry", "Robot", "RobotKindSetting", "Role",
    "RobotControl", "StoredPlan", "User", "UserPreference",
]
