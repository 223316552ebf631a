"""One driver's drive commands on one gRPC call (DriveStream), opened at the first command and kept while they drive.

A console sends a command every 50 ms: a unary Drive each was a whole call (its headers, its deadline, its call
object), about a third of a worker's interpreter time in a class of 50. Here each command is one message written
on the driver's call and answered by one message naming its sequence, answers coming in order.

Nothing of the command path changes: a refusal comes back as the status a unary Drive would have ended with and is
translated by the link's one map (`translate_status`), so the stale-token rule in `access/commands.py` applies as
before; the robot applies every command as it applies Drive's, so its deadman still stops the base when commands
stop, whether or not the call stays open. When the call breaks (the robot restarts, the network drops), the
command in hand goes as a unary Drive (a command the robot took already is ignored by its sequence), and so do the
next ones until the call is opened again, REOPEN_AFTER_S later; a robot without DriveStream (UNIMPLEMENTED) is
driven by unary calls and asked again after NOT_OFFERED_RETRY_S. Only `access/commands.py` drives through this.

A command waits for its answer ANSWER_WAIT_S (or the link's deadline, if longer), not the link's 1 s: the wait is
timed on the channel loop, so a worker whose loop is held up (a class on a busy machine) would count its own
lateness as the robot's, and the timeouts came in bursts (a unary call's deadline runs in gRPC's core, which the loop's
lateness does not reach). A robot that stops answering is caught by that wait, then the call is dropped and the
commands go as unary Drives; a connection that dies is caught by the channel's keepalive.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import time

import grpc

from middleware.robots.link import DriveResult, RobotLink, translate_status
from middleware.robots.refusals import RobotUnavailable
from protos.telelab.v1 import robot_pb2

log = logging.getLogger(__name__)
REOPEN_AFTER_S = 1.0  # after a call broke, commands go as unary Drives this long before a call is opened again
NOT_OFFERED_RETRY_S = 60.0  # a robot that does not offer DriveStream is asked again this much later
ANSWER_WAIT_S = 5.0  # how long a command on the call waits for its answer, timed on the loop (see above)


class CallBroken(Exception):
    """The driver's call ended before the command was answered: it goes as a unary Drive instead."""


class DriveStream:
    """One driver's commands to one robot on one DriveStream call, each answered by its sequence, with a unary Drive
    whenever the call cannot carry them. Used on one asyncio loop (the channel loop) only."""

    def __init__(self, link: RobotLink) -> None:
        self._link = link
        self._call: grpc.aio.StreamStreamCall | None = None
        self._reader: asyncio.Task[None] | None = None
        self._unanswered: collections.deque[tuple[int, asyncio.Future[robot_pb2.DriveStreamAck]]] = (
            collections.deque())
        self._writing = asyncio.Lock()
        self._unary_until = 0.0  # time.monotonic() before which commands go as unary Drives
        self._closed = False
        self.calls_opened = 0  # for tests and measurements
        self.unary_commands = 0

    async def drive(self, token: str, sequence: int, linear_mps: float, angular_radps: float) -> DriveResult:
        """Sends one drive command and waits for its answer (as RobotLink.drive_async: CommandRefused when the robot
        refuses it, RobotUnavailable when it cannot be reached or does not answer within the link's deadline)."""
        call = self._open()
        if call is None:
            return await self._unary(token, sequence, linear_mps, angular_radps)
        command = robot_pb2.DriveCommand(token=token, sequence=sequence, linear_mps=linear_mps,
                                         angular_radps=angular_radps)
        self._link.note_drive_sent(sequence)
        started = time.perf_counter()
        try:
            # The whole exchange under the deadline: it cancels the wait for the answer (its future, which the reader
            # then skips) or, in a write, the call itself (grpc.aio cancels a call whose write is cancelled).
            async with asyncio.timeout(max(self._link.rpc_timeout_s, ANSWER_WAIT_S)):
                answer = await (await self._send(call, command))
        except CallBroken:
            return await self._unary(token, sequence, linear_mps, angular_radps)
        except TimeoutError:
            self._drop(call, REOPEN_AFTER_S)  # the robot does not answer on it: unary calls meanwhile
            self._link.note_unreachable()
            raise translate_status(grpc.StatusCode.DEADLINE_EXCEEDED, "") from None
        round_trip_ms = (time.perf_counter() - started) * 1000
        if answer.WhichOneof("outcome") == "refusal":
            refusal = answer.refusal
            raise translate_status(_STATUS_CODES.get(refusal.status_code, grpc.StatusCode.UNKNOWN), refusal.message,
                                   refusal.field or None)
        ack = answer.ack
        self._link.note_drive_answer(ack.applied_sequence)
        return DriveResult(ack.applied_sequence, ack.linear_mps, ack.angular_radps, round_trip_ms)

    async def close(self) -> None:
        """Ends the call (the driver left); the robot's handler of it ends with it."""
        self._closed = True
        if self._call is not None:
            self._drop(self._call, reopen_after_s=0.0)
        if self._reader is not None:
            with contextlib.suppress(asyncio.CancelledError):
                await self._reader

    def _open(self) -> grpc.aio.StreamStreamCall | None:
        if self._call is not None:
            return self._call
        if self._closed or time.monotonic() < self._unary_until:
            return None
        try:
            call = self._link.open_drive_call()
        except RobotUnavailable:
            return None
        self._call = call
        self.calls_opened += 1
        self._reader = asyncio.get_running_loop().create_task(self._read_answers(call))
        return call

    async def _send(self, call: grpc.aio.StreamStreamCall,
                    command: robot_pb2.DriveCommand) -> asyncio.Future[robot_pb2.DriveStreamAck]:
        """Writes command on call; the future its answer resolves (CallBroken if the call ends first)."""
        answered: asyncio.Future[robot_pb2.DriveStreamAck] = asyncio.get_running_loop().create_future()
        async with self._writing:  # one write at a time, in the order the answers will come
            if not self._is_open(call):
                raise CallBroken
            self._unanswered.append((command.sequence, answered))
            try:
                await call.write(command)
            except (grpc.RpcError, asyncio.InvalidStateError, grpc.aio.UsageError) as error:
                log.info("a drive stream to %s broke on a write: %s", self._link.name, error)
                self._drop(call, REOPEN_AFTER_S)
                raise CallBroken from None
            except asyncio.CancelledError:
                task = asyncio.current_task()
                if task is not None and task.cancelling():
                    raise  # this command's wait was cancelled (its deadline): grpc.aio cancelled the call with it
                self._drop(call, REOPEN_AFTER_S)  # the call was cancelled under the write (dropped, closed)
                raise CallBroken from None
        return answered

    def _is_open(self, call: grpc.aio.StreamStreamCall) -> bool:
        return self._call is call

    async def _read_answers(self, call: grpc.aio.StreamStreamCall) -> None:
        """Hands each answer to the command it names (answers come in the order the commands were written)."""
        reopen_after_s = REOPEN_AFTER_S
        try:
            async for answer in call:
                while self._unanswered:
                    sequence, answered = self._unanswered.popleft()
                    if sequence == answer.sequence:
                        if not answered.done():
                            answered.set_result(answer)
                        break
                    if not answered.done():  # never answered: the robot lost it, so it goes again as a unary call
                        answered.set_exception(CallBroken())
        except grpc.RpcError as error:
            if error.code() == grpc.StatusCode.UNIMPLEMENTED:
                reopen_after_s = NOT_OFFERED_RETRY_S
            elif error.code() != grpc.StatusCode.CANCELLED:
                log.info("the drive stream to %s broke: %s", self._link.name, error.code())
        except asyncio.CancelledError:
            pass
        finally:
            self._drop(call, reopen_after_s)

    def _drop(self, call: grpc.aio.StreamStreamCall, reopen_after_s: float) -> None:
        """Ends call: its unanswered commands go as unary Drives, and so do the next ones for reopen_after_s."""
        if call is self._call:
            self._call = None
            self._unary_until = time.monotonic() + reopen_after_s
        call.cancel()
        while self._unanswered:
            _sequence, answered = self._unanswered.popleft()
            if not answered.done():
                answered.set_exception(CallBroken())

    async def _unary(self, token: str, sequence: int, linear_mps: float, angular_radps: float) -> DriveResult:
        self.unary_commands += 1
        return await self._link.drive_async(token, sequence, linear_mps, angular_radps)


_STATUS_CODES = {code.value[0]: code for code in grpc.StatusCode}
