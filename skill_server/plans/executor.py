"""Runs a checked plan as one motor goal: a tree of blocks (the sequencer's StepSequence) whose leaves are the
plan's lines, each naming its line in feedback, events and failures.

Skill lines build the skill's controller through the registry, as ActivateSkill does; every wheel command goes
out through the sequencer's own limits after the plan's `set` limits. `set watchdog S` sets the base's drive
watchdog (the time a direct drive command lasts without a newer one, as SetLimits sets it) for the rest of the plan,
given back when the plan ends however it ends. The plan's sim time is capped.

`on <event> { body }` arms a handler when the plan reaches it, for the lines after it in its block (their handlers
are fixed when the block is built: the nearest on of each event wins). A line in scope is cut short in the tick its
event happens (its controller stopped, its outcome of that tick dropped), the body runs in its place, and the block
goes on with the next line. obstacle_detected and battery_low are the plan's own watches (the detect_obstacle
skill's controller, a charge threshold), fresh each time their on line is reached; wall_lost and goal_reached come
from the line's own skill, localized from a localization goal running beside the plan (the sequencer's
EventManager). Lines of a body have no handlers, so no event is handled while one runs.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

from skill_server.goals import EventKind, GoalFeedback, GoalStatus
from skill_server.plans.model import (
    DriveLine,
    IfLine,
    OnLine,
    PlanLine,
    RepeatLine,
    SayLine,
    SetLine,
    SkillLine,
    WaitLine,
)
from skill_server.plans.steps import (
    BatteryWatch,
    DriveWatchdog,
    Instant,
    PlanSettings,
    TimedDrive,
    Wait,
    WatchdogChange,
    condition_holds,
    describe_condition,
)
from skill_server.plans.validation import EVENTS, CheckedPlan
from skill_server.sim.robot_model import RobotSpec
from skill_server.skills.base import (
    Outcome,
    SkillController,
    SkillStep,
    TickInput,
    aborted,
    feedback_for,
    succeeded,
)
from skill_server.skills.events import EventManager
from skill_server.skills.perception import Perception
from skill_server.skills.registry import SkillRegistry
from skill_server.skills.sequence import StepFactory, StepSequence

MAX_PLAN_S = 1800.0  # sim time; then ABORTED TIMEOUT
STEPS_STARTED_PER_TICK = 50  # lines done in no time (set, say, if) chain within one tick up to this many


@dataclass(frozen=True)
class SkillStepTiming:
    """When a skill line began and when its skill's controller had been built and ticked (perf_counter s)."""

    line: int
    skill: str
    step_started_s: float
    skill_started_s: float


PlanObserver = Callable[[SkillStepTiming], None]
Handlers = dict[str, OnLine]  # the handler in force for each event, for the lines of a block
WATCHED_EVENTS = ("obstacle_detected", "battery_low")  # the plan watches these itself; the others come from skills
# the plan-language name of the skills' events an on can handle (obstacle_detected and battery_low are watched)
EVENT_OF_KIND = {EventKind.WALL_LOST: "wall_lost", EventKind.GOAL_REACHED: "goal_reached",
                 EventKind.CONVERGED: "localized"}


class PlanContext:
    """What the lines of one plan share: the robot, the settings in force, the last skill's result."""

    def __init__(self, registry: SkillRegistry, perception: Perception, spec: RobotSpec,
                 observer: PlanObserver | None, watchdog: DriveWatchdog | None = None,
                 events: EventManager | None = None) -> None:
        self.registry = registry
        self.events = events
        self.watches: dict[int, tuple[OnLine, SkillController | BatteryWatch]] = {}  # armed, by id of the on line
        self.fired: dict[int, str] = {}  # this tick: the armed watches that fired, what they saw
        self.happened: dict[str, str] = {}  # this tick: the skills' events beside the plan, by name
        self.perception = perception
        self.settings = PlanSettings(spec.max_linear_mps, spec.max_angular_radps)
        self.observer = observer
        self.watchdog = watchdog
        self.watchdog_change: WatchdogChange | None = None  # the base's watchdog as this plan set it
        self.goal_reached = False  # the last skill line ended reaching its goal
        self.line = 0  # the line running now
        self.starts_left = STEPS_STARTED_PER_TICK

    def build_skill(self, line: SkillLine) -> SkillController:
        """The skill's controller from its validated parameters, built as ActivateSkill builds it."""
        return self.registry.entry(line.skill).build(dict(line.parameters), self.perception)

    def apply(self, line: SetLine) -> str:
        """A setting for the rest of the plan."""
        if line.setting == "max_speed":
            self.settings.max_linear_mps = line.value
        elif line.setting == "max_turn_rate":
            self.settings.max_angular_radps = line.value
        else:
            change = self.watchdog.change(line.value, self.watchdog_change) if self.watchdog is not None else None
            if change is None:
                return "the watchdog was not changed: this robot has no controller to set it for"
            self.watchdog_change = change
            return f"the base's drive watchdog set to {line.value:g} s until the plan ends"
        return f"{line.setting} set to {line.value:g}"

    def arm(self, line: OnLine) -> str:
        """Reaching an on line: its watch starts afresh (an obstacle already near fires at the next tick)."""
        event = EVENTS[line.event]
        value = line.value or event.default
        if line.event == "obstacle_detected":
            entry = self.registry.entry(event.skill)
            watch: SkillController | BatteryWatch = entry.build(
                entry.description.validate({"warning_distance_m": value}), self.perception)
            self.watches[id(line)] = (line, watch)
            return f"watching for an obstacle within {value:g} m until the end of its block"
        if line.event == "battery_low":
            self.watches[id(line)] = (line, BatteryWatch(value))
            return f"watching for the battery below {value:g} until the end of its block"
        return f"listening for {line.event} until the end of its block"

    def begin_tick(self, tick: TickInput) -> list[tuple[EventKind, str]]:
        """Ticks the armed watches and reads the events of the goals beside the plan; what fired, to announce."""
        self.fired, self.happened = {}, {}
        announced: list[tuple[EventKind, str]] = []
        for key, (line, watch) in list(self.watches.items()):
            if isinstance(watch, BatteryWatch):
                seen = watch.fired(tick)
                kind = EventKind.BATTERY_LOW
            else:
                step = watch.tick(tick)
                seen = next((m for k, m in step.events if k is EventKind.OBSTACLE_DETECTED), None)
                kind = EventKind.OBSTACLE_DETECTED
            if seen is not None:
                self.fired[key] = seen
                announced.append((kind, f"{seen} (the on of line {line.line})"))
        for event in self.events.published() if self.events is not None else ():
            self.happened.setdefault(EVENT_OF_KIND.get(event.kind, ""), f"{event.skill}: {event.message}")
        self.happened.pop("", None)
        return announced

    def happening(self, handlers: Handlers, own: tuple[tuple[EventKind, str], ...]) -> tuple[OnLine, str] | None:
        """The handler to run now for a line in scope of handlers, and what happened; own: the line's events."""
        for name, line in handlers.items():
            if name in WATCHED_EVENTS:
                seen = self.fired.get(id(line))
            else:
                seen = next((m for k, m in own if EVENT_OF_KIND.get(k) == name), self.happened.get(name))
            if seen is not None:
                return line, seen
        return None

    def stop_watches(self) -> None:
        """The plan ended: the watches' controllers are released."""
        for _, watch in self.watches.values():
            if isinstance(watch, SkillController):
                watch.stop()
        self.watches.clear()

    def give_back_watchdog(self) -> None:
        """The plan ended: the base's watchdog is what it was before the plan's first `set watchdog`."""
        change, self.watchdog_change = self.watchdog_change, None
        if change is not None and self.watchdog is not None:
            self.watchdog.restore(change)


class PlanBlock(StepSequence):
    """A block of lines: the sequencer's step sequence, with the lines naming themselves."""

    def __init__(self, steps: list[tuple[str, StepFactory]], context: PlanContext) -> None:
        super().__init__(steps)
        self._context = context

    def relay_event(self, kind: EventKind, message: str) -> None:
        """The lines' events already name their line."""
        self.announce(kind, message)

    def step_feedback(self, tick: TickInput, step: GoalFeedback, progress: float) -> GoalFeedback:
        """The line's feedback with the block's progress."""
        return replace(step, progress=min(1.0, max(0.0, progress)))

    def step_failed(self, outcome: Outcome) -> Outcome:
        """The line's failure already names it."""
        return outcome

    def all_done(self, last: Outcome) -> Outcome:
        """Every line of the block succeeded."""
        return succeeded(f"{len(self._steps)} lines done")

    def step_started(self) -> None:
        """Each line announces itself."""

    def advance_at_once(self) -> bool:
        """The next line starts in this tick while the tick's budget lasts: no stop between lines."""
        self._context.starts_left -= 1
        return self._context.starts_left > 0


class LineRunner(SkillController):
    """One leaf line: its controller, its line in feedback and failures, and a skill's time limit."""

    def __init__(self, context: PlanContext, line: PlanLine, what: str, build: Callable[[], SkillController],
                 started_message: str | None = None, duration_s: float = 0.0, handlers: Handlers | None = None) -> None:
        super().__init__()
        self._context, self._line, self._what, self._build = context, line, what, build
        self._started_message = started_message if started_message is not None else what
        self._duration_s = duration_s
        self._handlers = handlers or {}
        self._inner: SkillController | None = None
        self._handler: tuple[OnLine, PlanBlock] | None = None  # the on body running in this line's place
        self._started_s = 0.0

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Ticks the line's controller (or the on body that cut it short) and names the line in what it reports."""
        if self._handler is not None:
            return self._run_handler(tick)
        if self._inner is not None:
            step = self._inner.tick(tick)
        else:
            step_started_s = time.perf_counter()
            self._context.line, self._started_s = self._line.line, tick.sim_time_s
            self.announce(EventKind.STEP_STARTED, f"line {self._line.line}: {self._started_message}")
            self._inner = self._build()
            step = self._inner.tick(tick)
            if isinstance(self._line, SkillLine) and self._context.observer is not None:
                self._context.observer(SkillStepTiming(self._line.line, self._line.skill, step_started_s,
                                                       time.perf_counter()))
        happening = self._context.happening(self._handlers, step.events) if self._handlers else None
        if happening is not None:
            if isinstance(self._line, SkillLine) and step.outcome is not None:
                self._context.goal_reached = step.outcome.status is GoalStatus.SUCCEEDED and step.outcome.reached
            return self._start_handler(tick, *happening)
        return self._report(tick, step)

    def _start_handler(self, tick: TickInput, on: OnLine, seen: str) -> tuple[float, float, Outcome | None,
                                                                              GoalFeedback]:
        """The event of on happened: this line is cut short and on's body runs in its place."""
        if self._inner is not None:
            self._inner.stop()
        self.announce(EventKind.HANDLED, f"line {self._line.line} cut short by {on.event} ({seen}): the on of line "
                                         f"{on.line} runs")
        self._handler = (on, PlanBlock(block_steps(on.body, self._context, {}), self._context))
        return self._run_handler(tick)

    def _run_handler(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        assert self._handler is not None
        on, block = self._handler
        step = block.tick(tick)
        for kind, message in step.events:
            self.announce(kind, message)
        feedback = step.feedback or GoalFeedback()
        if step.outcome is not None and step.outcome.status is GoalStatus.SUCCEEDED:
            return 0.0, 0.0, succeeded(f"line {self._line.line} cut short by {on.event}; the on of line {on.line} "
                                       "done"), feedback
        return step.linear_mps, step.angular_radps, step.outcome, feedback

    def _report(self, tick: TickInput, step: SkillStep) -> tuple[float, float, Outcome | None, GoalFeedback]:
        number, outcome = self._line.line, step.outcome
        for kind, message in step.events:
            if kind is not EventKind.GOAL_REACHED:
                self.announce(kind, f"line {number}: {message}")
        inner = step.feedback or GoalFeedback()
        state = f"line {number}: {self._what}" + (f": {inner.state}" if inner.state else "")
        values = {**dict(inner.values), "line": float(number)}
        # replace() keeps whatever else the skill reports (its planned path) as it is.
        reported = replace(inner, sim_time_s=tick.sim_time_s, state=state, pose=tick.pose,
                           pose_source=tick.pose_source, values=tuple(sorted(values.items())))
        elapsed_s = tick.sim_time_s - self._started_s
        is_skill = isinstance(self._line, SkillLine)
        if outcome is not None:
            if is_skill:
                self._context.goal_reached = outcome.status is GoalStatus.SUCCEEDED and outcome.reached
            if outcome.status is not GoalStatus.SUCCEEDED:
                return 0.0, 0.0, Outcome(outcome.status, outcome.error_code,
                                         f"line {number}: {outcome.message}"), reported
            return 0.0, 0.0, succeeded(f"line {number}: {outcome.message}"), reported
        if self._duration_s > 0 and elapsed_s >= self._duration_s - 1e-9:
            self._context.goal_reached = False
            return 0.0, 0.0, succeeded(f"line {number}: ran for {self._duration_s:g} s"), reported
        return step.linear_mps, step.angular_radps, None, reported

    def stop(self) -> None:
        """Releases what the line's controller (or the on body running in its place) holds."""
        if self._inner is not None:
            self._inner.stop()
        if self._handler is not None:
            self._handler[1].stop()


class BlockLine(SkillController):
    """A repeat or an if: announces its line, then runs the block it chose when it was reached."""

    def __init__(self, context: PlanContext, line: PlanLine, what: str,
                 choose: Callable[[TickInput], tuple[str, list[tuple[str, StepFactory]]]]) -> None:
        super().__init__()
        self._context, self._line, self._what, self._choose = context, line, what, choose
        self._block: PlanBlock | None = None
        self._chosen = False

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Chooses on the first tick, then ticks the block."""
        number = self._line.line
        if not self._chosen:
            self._chosen = True
            self._context.line = number
            note, steps = self._choose(tick)
            self.announce(EventKind.STEP_STARTED, f"line {number}: {self._what}{note}")
            self._block = PlanBlock(steps, self._context) if steps else None
        if self._block is None:
            return 0.0, 0.0, succeeded(f"line {number}: nothing to do"), feedback_for(
                tick, f"line {number}: {self._what}", 1.0, line=float(number))
        step = self._block.tick(tick)
        for kind, message in step.events:
            self.announce(kind, message)
        return step.linear_mps, step.angular_radps, step.outcome, step.feedback or GoalFeedback()

    def stop(self) -> None:
        """Releases the line running inside the block."""
        if self._block is not None:
            self._block.stop()


def block_steps(lines: tuple[PlanLine, ...], context: PlanContext,
                handlers: Handlers) -> list[tuple[str, StepFactory]]:
    """The step factories of a block's lines (each builds its controller when the line is reached); handlers are
    the on lines in force from the enclosing blocks, and each on line adds its own for the lines after it."""
    steps: list[tuple[str, StepFactory]] = []
    for line in lines:
        steps.append((f"line {line.line}", _factory(line, context, handlers)))
        if isinstance(line, OnLine):
            handlers = {**handlers, line.event: line}
    return steps


def _factory(line: PlanLine, context: PlanContext, handlers: Handlers) -> StepFactory:
    if isinstance(line, SkillLine):
        what = line.skill + (f" for {line.duration_s:g} s" if line.duration_s else "")
        return lambda _: LineRunner(context, line, what, lambda: context.build_skill(line),
                                    duration_s=line.duration_s, handlers=handlers)
    if isinstance(line, DriveLine):
        what = f"drive {line.linear_mps:g} m/s {line.angular_radps:g} rad/s for {line.duration_s:g} s"
        return lambda _: LineRunner(context, line, what,
                                    lambda: TimedDrive(line.linear_mps, line.angular_radps, line.duration_s),
                                    handlers=handlers)
    if isinstance(line, WaitLine):
        what = "wait" + (f" until {describe_condition(line.condition)}" if line.condition else "") + (
            f" {'at most ' if line.condition else ''}{line.duration_s:g} s" if line.duration_s else "")
        return lambda _: LineRunner(context, line, what,
                                    lambda: Wait(line.condition, line.duration_s, lambda: context.goal_reached),
                                    handlers=handlers)
    if isinstance(line, SetLine):
        return lambda _: LineRunner(context, line, f"set {line.setting} {line.value:g}",
                                    lambda: Instant(lambda: context.apply(line)), handlers=handlers)
    if isinstance(line, SayLine):
        return lambda _: LineRunner(context, line, "say", lambda: Instant(lambda: "said"), started_message=line.text,
                                    handlers=handlers)
    if isinstance(line, OnLine):
        return lambda _: LineRunner(context, line, f"on {line.event}", lambda: Instant(lambda: context.arm(line)))
    if isinstance(line, RepeatLine):
        body = block_steps(line.body, context, handlers)
        return lambda _: BlockLine(context, line, f"repeat {line.count}", lambda tick: ("", body * line.count))
    assert isinstance(line, IfLine) and line.condition is not None  # validation refuses an if without one
    condition, branches = line.condition, (line.then_block, line.else_block)

    def choose(tick: TickInput) -> tuple[str, list[tuple[str, StepFactory]]]:
        holds = condition_holds(condition, tick, context.goal_reached)
        chosen = branches[0] if holds else branches[1]
        return (": yes, then" if holds else ": no, else"), block_steps(chosen, context, handlers)

    return lambda _: BlockLine(context, line, f"if {describe_condition(condition)}", choose)


class PlanRunner(SkillController):
    """A whole plan as one motor goal: its top block, the plan's limits on the wheels, and its time cap."""

    skill_class = "deliberative"  # the paper's task supervisor: it sequences the other skills

    def __init__(self, checked: CheckedPlan, registry: SkillRegistry, perception: Perception, spec: RobotSpec,
                 observer: PlanObserver | None = None, watchdog: DriveWatchdog | None = None,
                 events: EventManager | None = None) -> None:
        super().__init__()
        self._name = checked.plan.name
        self._context = PlanContext(registry, perception, spec, observer, watchdog, events)
        self._block = PlanBlock(block_steps(checked.plan.steps, self._context, {}), self._context)
        self._started_s: float | None = None

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Ticks the plan's top block and clamps its wheel command to the plan's settings."""
        if self._started_s is None:
            self._started_s = tick.sim_time_s
        context = self._context
        if tick.sim_time_s - self._started_s > MAX_PLAN_S:
            return 0.0, 0.0, aborted("TIMEOUT", f"line {context.line}: the plan ran past its limit of "
                                                f"{MAX_PLAN_S:g} s"), self.last_feedback
        context.starts_left = STEPS_STARTED_PER_TICK
        for kind, message in context.begin_tick(tick):
            self.announce(kind, message)
        step = self._block.tick(tick)
        for kind, message in step.events:
            self.announce(kind, message)
        feedback = step.feedback or GoalFeedback()
        if step.outcome is not None:
            if step.outcome.status is GoalStatus.SUCCEEDED:
                self.announce(EventKind.GOAL_REACHED, f"plan {self._name} done")
                return 0.0, 0.0, succeeded(f"plan {self._name} done; last: {step.outcome.message}"), feedback
            return 0.0, 0.0, step.outcome, feedback
        limits = context.settings
        linear = max(-limits.max_linear_mps, min(limits.max_linear_mps, step.linear_mps))
        angular = max(-limits.max_angular_radps, min(limits.max_angular_radps, step.angular_radps))
        return linear, angular, None, feedback

    def stop(self) -> None:
        """Releases the line running now and gives the base's watchdog back (the plan was cancelled, preempted or
        ended)."""
        self._block.stop()
        self._context.stop_watches()
        self._context.give_back_watchdog()

    def position(self) -> str:
        """The line running now: a cancel, a preemption or a revoked control names it."""
        return f"line {self._context.line}" if self._context.line else ""
