"""The one path from a user to a robot command, whatever its source (drive pad, skill panel, lesson cue,
tour step, practice robot, demo recorder).

It owns the controller token (the known-token fast path, a database re-read when the robot refuses it,
re-sending it to a robot that restarted and forgot it), sequence numbering and the deadman-friendly held
drive; a robot's refusal or absence is already a `Refused` (robots/refusals.py), so it passes. Nothing else in
the middleware calls a RobotLink command method (drive, activate_skill, cancel_goal, clear_map,
return_to_dock, place_robot, reset_evidence_grid, set_controller, set_limits, get_limits, run_plan):
tests/test_architecture.py checks it.

Supervisory actions (clearing the map, the return to the dock, placing the robot) are the controller's, or a
tutor's or an admin's at any time: those go out under whatever token the robot obeys now ("" while nobody has
control), so a tutor acts without taking anyone's turn.

The stale-token rule, the same for every source: a command goes out under the token this process last
knew; if the robot refuses it as not the controller's, the token is read again from its source (the
database for a lab robot); a different token means the turn moved on (retry with it, or refuse the user
as an observer), the same token means the robot forgot it (re-send it, then retry once).
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Awaitable, Callable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass
from dataclasses import field as dataclass_field
from typing import Any, Protocol, TypeVar

from flask import Flask, current_app
from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.errors import ApiError, Refused
from middleware.i18n import N_
from middleware.robots.drive_stream import DriveStream
from middleware.robots.link import DriveResult, RobotLink
from middleware.robots.refusals import NOT_CONTROLLER_MESSAGE, STALE_TOKEN_CODES, CommandRefused, RobotUnavailable
from middleware.robots.registry import PersonalRobot, RobotRegistry
from protos.telelab.v1 import robot_pb2

T = TypeVar("T")
log = logging.getLogger(__name__)
_EXTENSION_KEY = "telelab.commands"

MAX_DRIVE_HOLD_S = 10.0  # direct_control's own limit; a longer hold is renewed by its sender
MIN_DRIVE_HOLD_S = 0.1


NOBODY_IN_CONTROL_MESSAGE = N_("Nobody has control of this robot now: take a turn first (the Turn panel, on the "
                                "console or on this page, gives you one).")


class NotController(CommandRefused):
    """The user does not control the robot now (they observe, the turn moved on, or nobody holds it and they have
    not taken a turn: then the sentence says so, not "someone else has control")."""

    def __init__(self, field: str | None = None, nobody_controls: bool = False) -> None:
        super().__init__("not_controller", NOT_CONTROLLER_MESSAGE, field)
        self.field = field
        if nobody_controls:
            self.message = gettext(NOBODY_IN_CONTROL_MESSAGE)
            self.args = (self.message,)


class TokenSource(Protocol):
    """Where the token a user commands a robot under comes from."""

    def token(self, fresh: bool) -> str | None:
        """The user's token (fresh: re-read from the authority), or None when they do not control the robot."""

    def remembered(self) -> str | None:
        """token(False) when it needs no read nor lock (this process knows it); None: ask token() off the loop."""

    def resend(self, token: str) -> bool:
        """Hands the robot token again (it restarted and forgot it); False if that failed."""

    def nobody_controls(self) -> bool:
        """Whether nobody holds the robot now (a refusal then says to take a turn, not that someone else has it)."""


class Seats(Protocol):
    """The access coordinator as the command path sees it: who holds each robot's seat, and its token."""

    def controller_token(self, robot_name: str, user_id: int) -> str | None:
        """user_id's token if they control the robot now (read from the database)."""

    def known_controller_token(self, robot_name: str, user_id: int) -> str | None:
        """controller_token, without a read when this process knows user_id controls the robot."""

    def remembered_controller_token(self, robot_name: str, user_id: int) -> str | None:
        """user_id's token when this process knows they control the robot, else None (memory only)."""

    def resend_token(self, robot_name: str) -> bool:
        """Hands the robot its current controller's token again."""

    def current_token(self, robot_name: str) -> str:
        """The token the robot obeys now, whoever holds it ("" while nobody does)."""


class SeatTokens:
    """A shared robot's token: the user's round-robin seat, as the access coordinator keeps it."""

    def __init__(self, coordinator: Seats, robot_name: str, user_id: int) -> None:
        self._coordinator, self._robot_name, self._user_id = coordinator, robot_name, user_id

    def token(self, fresh: bool) -> str | None:
        """The known token (no database read) unless fresh; a "no" is always read from the database."""
        read = self._coordinator.controller_token if fresh else self._coordinator.known_controller_token
        return read(self._robot_name, self._user_id)

    def remembered(self) -> str | None:
        """The token this process knows the user holds, if it does."""
        return self._coordinator.remembered_controller_token(self._robot_name, self._user_id)

    def resend(self, token: str) -> bool:
        """Re-sends the current controller's token to the robot."""
        return self._coordinator.resend_token(self._robot_name)

    def nobody_controls(self) -> bool:
        """Whether the robot's seat is free (a database read: only on the way to a refusal)."""
        return self._coordinator.current_token(self._robot_name) == ""


class SupervisorTokens:
    """A supervisor's (tutor's, admin's) token for supervisory actions: whatever token the robot obeys now."""

    def __init__(self, coordinator: Seats, robot_name: str) -> None:
        self._coordinator, self._robot_name = coordinator, robot_name

    def token(self, fresh: bool) -> str | None:
        """The current controller's token, or "" while nobody has control (always read: supervision is rare)."""
        return self._coordinator.current_token(self._robot_name)

    def remembered(self) -> str | None:
        """Never: supervision always reads who holds the robot."""
        return None

    def resend(self, token: str) -> bool:
        """Re-sends the current controller's token to the robot."""
        return self._coordinator.resend_token(self._robot_name)

    def nobody_controls(self) -> bool:
        """A supervisor acts whoever holds the robot."""
        return False


class OwnerToken:
    """A robot with one controller for its whole life (a practice robot, the demo recorder's robot)."""

    def __init__(self, link: RobotLink, token: Callable[[], str],
                 still_ours: Callable[[], bool] = lambda: True) -> None:
        self._link, self._token, self._still_ours = link, token, still_ours

    def token(self, fresh: bool) -> str | None:
        """The owner's token."""
        return self._token() or None

    def remembered(self) -> str | None:
        """The owner's token (kept in memory)."""
        return self._token() or None

    def resend(self, token: str) -> bool:
        """Hands the robot the owner's token again, while the robot at the link's address is still the owner's: a
        farm that gave the address to another robot would otherwise hand that robot the old owner's token."""
        return self._still_ours() and hand_over(self._link, token)

    def nobody_controls(self) -> bool:
        """The owner always holds it."""
        return False


def hand_over(link: RobotLink, token: str) -> bool:
    """Tells the robot whose commands to obey (an empty token revokes control); False if it did not answer."""
    try:
        link.set_controller(token)
    except (RobotUnavailable, CommandRefused) as error:
        log.info("could not hand %s its controller token: %s", link.name, error)
        return False
    return True


@dataclass(frozen=True)
class CommandNote:
    """A command as it went to the robot (or was refused), for the observers create_app hands in (the recorder)."""

    robot_name: str
    user_id: int | None
    action: str  # drive, activate, run_plan, cancel, clear_map, return_to_dock, place_robot, ...
    sent_unix_s: float
    accepted: bool
    outcome: str  # the goal id or applied sequence; the refusal's code when refused
    source: str | None  # what command_source() named around the call; None: the observer infers it
    detail: dict[str, object] = dataclass_field(default_factory=dict)


# Called after each command with its note; it must not block (the live path waits for it).
CommandObserver = Callable[[CommandNote], None]
_command_source: ContextVar[str | None] = ContextVar("telelab_command_source", default=None)


@contextlib.contextmanager
def command_source(source: str) -> Iterator[None]:
    """Names the source (pad, skill_panel, cue, tour_step, plan, student_code, tutor) of the commands sent inside."""
    reset = _command_source.set(source)
    try:
        yield
    finally:
        _command_source.reset(reset)


# (robot name, user id) -> why the user may only drive the robot by hand now (an open delay trial), or None.
HandDrivingRule = Callable[[str, int], str | None]


class Oversight(Protocol):
    """Who besides its owner may reach a personal robot (a tutor of its owner's open class), and who holds it now
    (a tutor who took it over: the owner's commands are refused until it ends). create_app hands it in."""

    def oversees(self, robot_name: str, user_id: int) -> bool:
        """Whether user_id (not the owner) may watch the personal robot and act on it as a supervisor."""

    def held_by(self, robot_name: str) -> int | None:
        """The overseer who holds the personal robot now, or None (its owner commands it)."""

    def remembered_holder(self, robot_name: str) -> tuple[bool, int | None]:
        """(True, held_by()) when this process's answer is fresh (no read), else (False, None)."""


class HeldTokens:
    """A personal robot's owner token, given to whoever holds the robot now: its owner, or an overseer who took
    it over (everyone else observes)."""

    def __init__(self, owner: OwnerToken, held_by: Callable[[], int | None], user_id: int, owner_id: int,
                 remembered_holder: Callable[[], tuple[bool, int | None]] = lambda: (False, None)) -> None:
        self._owner, self._held_by, self._user_id, self._owner_id = owner, held_by, user_id, owner_id
        self._remembered_holder = remembered_holder

    def token(self, fresh: bool) -> str | None:
        """The owner's token while this user holds the robot."""
        holder = self._held_by()
        return self._owner.token(fresh) if (holder or self._owner_id) == self._user_id else None

    def remembered(self) -> str | None:
        """The owner's token when this process knows, fresh, that this user holds the robot."""
        known, holder = self._remembered_holder()
        return self._owner.remembered() if known and (holder or self._owner_id) == self._user_id else None

    def resend(self, token: str) -> bool:
        """Hands the robot the owner's token again."""
        return self._owner.resend(token)

    def nobody_controls(self) -> bool:
        """Someone always holds a personal robot."""
        return False


class Commander:
    """One user's commands to one robot, under the token its source gives, with the stale-token rule.

    field names the robot in the request that asked (a refusal as an observer names it). hand_only, when given,
    says why the user may only drive by hand now: a motor skill other than direct control, a plan, a placement
    or a return to the dock is then refused, whatever sent it.
    """

    def __init__(self, link: RobotLink, tokens: TokenSource, field: str | None = None,
                 hand_only: Callable[[], str | None] | None = None, user_id: int | None = None,
                 observers: tuple[CommandObserver, ...] = ()) -> None:
        self.link, self._tokens, self._field = link, tokens, field
        self._hand_only = hand_only
        self._user_id, self._observers = user_id, observers
        # The paper's second leg: how long this commander's last command spent in its calls to the robot [ms].
        self.robot_round_trip_ms: float | None = None
        # The driver's commands from the drive channel, on one call to the robot, opened at the first (drive_async).
        self.drive_stream: DriveStream | None = None

    @property
    def robot_name(self) -> str:
        """The robot's name."""
        return self.link.name

    def is_controller(self) -> bool:
        """Whether the user controls the robot now (the known token; a "no" is read from the source)."""
        return self._tokens.token(fresh=False) is not None

    def drive(self, sequence: int, linear_mps: float, angular_radps: float) -> DriveResult:
        """A direct drive command (the robot's deadman stops the base when they stop coming)."""
        return self._as_controller(lambda token: self.link.drive(token, sequence, linear_mps, angular_radps),
                                   "drive", {"sequence": sequence, "linear_mps": linear_mps,
                                             "angular_radps": angular_radps})

    async def drive_async(self, sequence: int, linear_mps: float, angular_radps: float,
                          blocking: Callable[..., Awaitable[Any]]) -> DriveResult:
        """drive() for a caller on the channel loop (the drive channel): the command reaches the robot over grpc.aio on
        the loop, so no thread waits for the robot, on this driver's one drive stream (opened at the first command,
        ended by end_driving; a unary Drive whenever the stream cannot carry it); the token's lookups, which may read
        the database, go through blocking (`await blocking(fn, *args)`: the loop's pool). The same stale-token rule
        and notes as drive()."""
        detail: dict[str, object] = {"sequence": sequence, "linear_mps": linear_mps, "angular_radps": angular_radps}
        sent_unix_s = time.time()
        try:
            result = await self._drive_on_loop(sequence, linear_mps, angular_radps, blocking)
        except Refused as refused:
            if self._observers:
                self._tell(CommandNote(self.link.name, self._user_id, "drive", sent_unix_s, False, refused.code,
                                       _command_source.get(), detail))
            raise
        if self._observers:
            self._tell(CommandNote(self.link.name, self._user_id, "drive", sent_unix_s, True, _outcome(result),
                                   _command_source.get(), detail))
        return result

    async def _drive_on_loop(self, sequence: int, linear_mps: float, angular_radps: float,
                             blocking: Callable[..., Awaitable[Any]]) -> DriveResult:
        """_as_controller_unobserved's rule for a drive, awaited."""
        self.robot_round_trip_ms = None

        if self.drive_stream is None:
            self.drive_stream = DriveStream(self.link)
        stream = self.drive_stream

        async def attempt(token: str) -> DriveResult:
            started = time.perf_counter()
            try:
                return await stream.drive(token, sequence, linear_mps, angular_radps)
            finally:
                self.robot_round_trip_ms = (self.robot_round_trip_ms or 0.0) + (time.perf_counter() - started) * 1000

        token = self._tokens.remembered()  # the usual case, 20 times a second: no thread, no read
        if token is None:
            token = await blocking(self._tokens.token, False)
        if token is None:
            raise NotController(self._field, await blocking(self._tokens.nobody_controls))
        try:
            return await attempt(token)
        except CommandRefused as refused:
            if refused.reason not in STALE_TOKEN_CODES:
                raise
            fresh = await blocking(self._tokens.token, True)
            if fresh is None:
                raise NotController(self._field, await blocking(self._tokens.nobody_controls)) from None
            if fresh == token and not await blocking(self._tokens.resend, fresh):
                raise
        return await attempt(fresh)

    async def end_driving(self) -> None:
        """Ends the driver's drive stream (their drive channel closed); the robot's deadman covers what follows."""
        if self.drive_stream is not None:
            await self.drive_stream.close()

    def stop(self) -> DriveResult:
        """A zero drive, which preempts any motor goal at once; numbered again above the robot's when another
        process sent this token a newer sequence (the robot ignored the first as older)."""
        sequence = self.link.next_sequence()
        result = self.drive(sequence, 0.0, 0.0)
        if result.applied_sequence > sequence:
            result = self.drive(self.link.next_sequence(), 0.0, 0.0)
        return result

    def activate(self, skill: str, parameters: dict[str, object], preempt: bool) -> robot_pb2.GoalState:
        """Starts a skill as a goal."""
        if skill != "direct_control" and any(s.name == skill and s.motor for s in self.link.skills()):
            self._refuse_unless_by_hand_allowed()
        return self._as_controller(lambda token: self.link.activate_skill(token, skill, parameters, preempt),
                                   "activate", {"skill": skill, "parameters": parameters})

    def run_plan(self, name: str, plan: robot_pb2.PlanBlock, preempt: bool) -> robot_pb2.GoalState:
        """Starts a checked plan as one motor goal "plan:<name>"."""
        self._refuse_unless_by_hand_allowed()
        return self._as_controller(lambda token: self.link.run_plan(token, name, plan, preempt),
                                   "run_plan", {"plan_name": name})

    def hold_drive(self, linear_mps: float, angular_radps: float, hold_s: float) -> robot_pb2.GoalState:
        """A drive held for hold_s (0.1 to 10 s) as a direct_control goal: it stops by itself if its sender goes."""
        hold = min(MAX_DRIVE_HOLD_S, max(MIN_DRIVE_HOLD_S, hold_s))
        return self.activate("direct_control", {"linear_mps": linear_mps, "angular_radps": angular_radps,
                                                "duration_s": round(hold, 3)}, preempt=True)

    def cancel(self, goal_id: str) -> robot_pb2.GoalState:
        """Cancels a goal; its message reports the error left."""
        return self._as_controller(lambda token: self.link.cancel_goal(token, goal_id), "cancel",
                                   {"goal_id": goal_id})

    def clear_map(self) -> list[str]:
        """Forgets the robot's map (for everyone after); the ids of the mapping and localization goals it ended."""
        return self._as_controller(self.link.clear_map, "clear_map")

    def return_to_dock(self) -> robot_pb2.ReturnToDockResponse:
        """Carries the robot to its dock: every goal ends, odometry restarts at the dock."""
        self._refuse_unless_by_hand_allowed()
        return self._as_controller(self.link.return_to_dock, "return_to_dock")

    def restart(self) -> robot_pb2.RestartResponse:
        """Restarts the robot's process (telemaintenance): its goals end, it comes back at its dock, same controller."""
        return self._as_controller(self.link.restart, "restart")

    def place_robot(self, pose: robot_pb2.Pose2D, kidnap: bool = False) -> robot_pb2.PlaceRobotResponse:
        """Places the robot at pose (refused naming the field unless it fits there): every goal ends, odometry
        restarts at the pose (kidnap: odometry goes on from where the robot believed it was)."""
        self._refuse_unless_by_hand_allowed()
        return self._as_controller(lambda token: self.link.place_robot(token, pose, kidnap), "place_robot",
                                   {"x_m": pose.x_m, "y_m": pose.y_m, "theta_rad": pose.theta_rad, "kidnap": kidnap})

    def reset_evidence(self) -> robot_pb2.EvidenceGrid:
        """Forgets the robot's teleperception evidence grid and readings (for every viewer); the emptied grid."""
        return self._as_controller(self.link.reset_evidence_grid, "reset_evidence")

    def limits(self) -> robot_pb2.Limits:
        """The velocity ceilings and the watchdog in force (reading needs no control)."""
        return self.link.get_limits()

    def set_limits(self, max_linear_mps: float, max_angular_radps: float, watchdog_s: float) -> robot_pb2.Limits:
        """Changes the robot's limits as its controller (0 keeps a value); the limits in force afterwards."""
        return self._as_controller(lambda token: self.link.set_limits(token, max_linear_mps, max_angular_radps,
                                                                      watchdog_s), "set_limits",
                                   {"max_linear_mps": max_linear_mps, "max_angular_radps": max_angular_radps,
                                    "watchdog_s": watchdog_s})

    def goal_state(self, goal_id: str) -> robot_pb2.GoalState:
        """A goal's state (reading needs no control)."""
        return self.link.get_goal(goal_id)

    def _refuse_unless_by_hand_allowed(self) -> None:
        reason = self._hand_only() if self._hand_only is not None else None
        if reason:
            raise Refused(409, "hand_driving_only", reason, self._field)

    def _as_controller(self, call: Callable[[str], T], action: str = "",
                       detail: dict[str, object] | None = None) -> T:
        if not self._observers:
            return self._as_controller_unobserved(call)
        sent_unix_s = time.time()
        try:
            result = self._as_controller_unobserved(call)
        except Refused as refused:
            self._tell(CommandNote(self.link.name, self._user_id, action, sent_unix_s, False, refused.code,
                                   _command_source.get(), detail or {}))
            raise
        self._tell(CommandNote(self.link.name, self._user_id, action, sent_unix_s, True, _outcome(result),
                               _command_source.get(), detail or {}))
        return result

    def _tell(self, note: CommandNote) -> None:
        for observer in self._observers:
            try:
                observer(note)
            except Exception:  # noqa: BLE001 - an observer's failure never fails the command
                log.exception("a command observer failed")

    def _as_controller_unobserved(self, call: Callable[[str], T]) -> T:
        self.robot_round_trip_ms = None
        timed = self._timed(call)
        token = self._tokens.token(fresh=False)
        if token is None:
            raise NotController(self._field, self._tokens.nobody_controls())
        try:
            return timed(token)
        except CommandRefused as refused:
            if refused.reason not in STALE_TOKEN_CODES:
                raise
            fresh = self._tokens.token(fresh=True)
            if fresh is None:
                raise NotController(self._field, self._tokens.nobody_controls()) from None
            if fresh == token and not self._tokens.resend(fresh):
                raise
        return timed(fresh)

    def _timed(self, call: Callable[[str], T]) -> Callable[[str], T]:
        """call, adding the time each attempt spends at the robot to robot_round_trip_ms (a retry's too: the
        person waited for both)."""
        def attempt(token: str) -> T:
            started = time.perf_counter()
            try:
                return call(token)
            finally:
                spent_ms = (time.perf_counter() - started) * 1000
                self.robot_round_trip_ms = (self.robot_round_trip_ms or 0.0) + spent_ms
        return attempt


def _outcome(result: object) -> str:
    """What a command's answer says in a note: the goal it started, or the sequence in force."""
    if isinstance(result, robot_pb2.GoalState):
        return result.goal_id
    if isinstance(result, DriveResult):
        return str(result.applied_sequence)
    return ""


class RobotCommands:
    """Finds the robots a user may reach and gives their commands the right token source."""

    def __init__(self, registry: RobotRegistry, coordinator: Seats,
                 hand_rules: tuple[HandDrivingRule, ...] = (), observers: tuple[CommandObserver, ...] = ()) -> None:
        self._registry, self._coordinator, self._hand_rules = registry, coordinator, hand_rules
        self._observers = observers

    def observe(self, observer: CommandObserver) -> None:
        """Adds an observer every later command is told of (create_app hands in the recorder's)."""
        self._observers = (*self._observers, observer)

    _oversight: Oversight | None = None

    def oversee(self, oversight: Oversight) -> None:
        """Lets overseers (a class's tutors, by create_app's hook) reach personal robots and take them over."""
        self._oversight = oversight

    def reachable(self, robot_name: str, user_id: int | None) -> RobotLink | None:
        """The robot's link if user_id may see it: any lab robot, a personal robot for its owner (and its
        overseers: a tutor of the owner's open class) only."""
        if not self._registry.is_personal_name(robot_name):
            return self._registry.get(robot_name)
        personal = self._registry.personal(robot_name)  # one lookup gives the link and the owner
        if personal is None:
            return None
        return personal.link if personal.owner_id == user_id or self._oversees(robot_name, user_id) else None

    def _oversees(self, robot_name: str, user_id: int | None) -> bool:
        return self._oversight is not None and user_id is not None and self._oversight.oversees(robot_name, user_id)

    def _personal_tokens(self, link: RobotLink, personal: PersonalRobot, user_id: int) -> TokenSource:
        """The owner's token, to whoever holds the personal robot now (its owner, or an overseer who took it over)."""
        owner = self._owner_token(link, personal)
        oversight = self._oversight
        if oversight is None:
            return owner
        return HeldTokens(owner, lambda: oversight.held_by(link.name), user_id, personal.owner_id,
                          lambda: oversight.remembered_holder(link.name))

    def _owner_token(self, link: RobotLink, personal: PersonalRobot) -> OwnerToken:
        """The personal robot's owner token, handed back to it only while the registry still says the robot at
        link's address is that owner's (a fresh lookup: a resend happens once per refusal, never per command)."""
        def still_ours() -> bool:
            now = self._registry.personal(link.name)
            return now is not None and now.token == personal.token and now.link.address == link.address
        return OwnerToken(link, lambda: personal.token, still_ours)

    def require(self, robot_name: str, user_id: int | None, field: str = "robot_name") -> RobotLink:
        """reachable(), or a 404 naming field (a robot of someone else's is answered like a missing one)."""
        link = self.reachable(robot_name, user_id)
        if link is None:
            raise ApiError(404, "unknown_robot", gettext("There is no robot named %(value)s.",
                                                         value=repr(robot_name[:64])), field)
        return link

    def for_user(self, robot_name: str, user_id: int, field: str = "robot_name") -> Commander:
        """The user's commands to the robot (a 404 if they may not see it)."""
        link = self.require(robot_name, user_id, field)
        hand_only = self._hand_only(robot_name, user_id)
        personal = self._registry.personal(robot_name)
        if personal is not None:
            return Commander(link, self._personal_tokens(link, personal, user_id), field, hand_only, user_id,
                             self._observers)
        return Commander(link, SeatTokens(self._coordinator, robot_name, user_id), field, hand_only, user_id,
                         self._observers)

    def _hand_only(self, robot_name: str, user_id: int) -> Callable[[], str | None]:
        return lambda: next((reason for rule in self._hand_rules if (reason := rule(robot_name, user_id))), None)


    def for_supervision(self, robot_name: str, user_id: int, supervisor: bool,
                        field: str = "robot_name") -> Commander:
        """The user's supervisory actions on the robot: as its controller, or, for a supervisor (a tutor or an
        admin) on a lab robot, under the robot's current token. Anyone else is refused as an observer."""
        commander = self.for_user(robot_name, user_id, field)
        personal = self._registry.personal(robot_name)
        if personal is not None and supervisor and personal.owner_id != user_id and self._oversees(robot_name,
                                                                                                  user_id):
            # A class's tutor stops or docks a student's robot whoever holds it.
            return Commander(commander.link, self._owner_token(commander.link, personal), field)
        if not supervisor or personal is not None or commander.is_controller():
            return commander
        return Commander(commander.link, SupervisorTokens(self._coordinator, robot_name), field,
                         self._hand_only(robot_name, user_id), user_id,
                         tuple(_as_tutor(observer) for observer in self._observers))


    def for_maintenance(self, robot_name: str, field: str = "robot_name") -> Commander:
        """Maintenance of the robot for someone the caller found may maintain it (an admin, a tutor of its courses):
        under its owner's token for a personal robot, else under the current controller's, whoever holds it."""
        link = self._registry.get(robot_name)
        if link is None:
            raise ApiError(404, "unknown_robot", gettext("There is no robot named %(value)s.",
                                                         value=repr(robot_name[:64])), field)
        personal = self._registry.personal(robot_name)
        if personal is not None:
            return Commander(link, self._owner_token(link, personal), field)
        return Commander(link, SupervisorTokens(self._coordinator, robot_name), field, observers=tuple(
            _as_tutor(observer) for observer in self._observers))


def _as_tutor(observer: CommandObserver) -> CommandObserver:
    """observer, told a supervisor's command came from a tutor unless its sender named another source."""
    def tell(note: CommandNote) -> None:
        observer(note if note.source else CommandNote(note.robot_name, note.user_id, note.action, note.sent_unix_s,
                                                      note.accepted, note.outcome, "tutor", note.detail))
    return tell


def owned_robot(link: RobotLink, token: str) -> Commander:
    """Commands to a robot this process owns outright (the demo recorder's), after handing it token."""
    if not hand_over(link, token):
        raise RobotUnavailable(gettext("%(robot)s did not take its controller token.", robot=link.name))
    return Commander(link, OwnerToken(link, lambda: token))


def init_app(app: Flask, registry: RobotRegistry, coordinator: Seats,
             hand_rules: tuple[HandDrivingRule, ...] = ()) -> None:
    """Creates app's command path over its registry and access coordinator, with the rules that may keep a user to
    driving by hand."""
    app.extensions[_EXTENSION_KEY] = RobotCommands(registry, coordinator, hand_rules)


def robot_commands(app: Flask | None = None) -> RobotCommands:
    """The command path of app (or of the current app)."""
    return (app or current_app).extensions[_EXTENSION_KEY]
