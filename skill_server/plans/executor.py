"""Runs a checked plan as one motor goal: a tree of blocks (the sequencer's StepSequence) whose leaves are the
plan's lines, each naming its line in feedback, events and failures.

Skill lines build the skill's controller through the registry, as ActivateSkill does; every wheel command goes
out through the sequencer's own limits after the plan's `set` limits. `set watchdog S` sets the base's drive
watchdog (the time a direct drive command lasts without a newer one, as SetLimits sets it) for the rest of the plan,
given back when the plan ends however it ends. The plan's sim time is capped.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

from skill_server.goals import EventKind, GoalFeedback, GoalStatus
from skill_server.plans.model import DriveLine, IfLine, PlanLine, RepeatLine, SayLine, SetLine, SkillLine, WaitLine
from skill_server.plans.steps import (
    DriveWatchdog,
    Instant,
    PlanSettings,
    TimedDrive,
    Wait,
    WatchdogChange,
    condition_holds,
    describe_condition,
)
from skill_server.plans.validation import CheckedPlan
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


class PlanContext:
    """What the lines of one plan share: the robot, the settings in force, the last skill's result."""

    def __init__(self, registry: SkillRegistry, perception: Perception, spec: RobotSpec,
                 observer: PlanObserver | None, watchdog: DriveWatchdog | None = None) -> None:
        self.registry = registry
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
                 started_message: str | None = None, duration_s: float = 0.0) -> None:
        super().__init__()
        self._context, self._line, self._what, self._build = context, line, what, build
        self._started_message = started_message if started_message is not None else what
        self._duration_s = duration_s
        self._inner: SkillController | None = None
        self._started_s = 0.0

    def control(self, tick: TickInput) -> tuple[float, float, Outcome | None, GoalFeedback]:
        """Ticks the line's controller and names the line in what it reports."""
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
        return self._report(tick, step)

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
        """Releases what the line's controller holds."""
        if self._inner is not None:
            self._inner.stop()


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


def block_steps(lines: tuple[PlanLine, ...], context: PlanContext) -> list[tuple[str, StepFactory]]:
    """The step factories of a block's lines (each builds its controller when the line is reached)."""
    return [(f"line {line.line}", _factory(line, context)) for line in lines]


def _factory(line: PlanLine, context: PlanContext) -> StepFactory:
    if isinstance(line, SkillLine):
        what = line.skill + (f" for {line.duration_s:g} s" if line.duration_s else "")
        return lambda _: LineRunner(context, line, what, lambda: context.build_skill(line),
                                    duration_s=line.duration_s)
    if isinstance(line, DriveLine):
        what = f"drive {line.linear_mps:g} m/s {line.angular_radps:g} rad/s for {line.duration_s:g} s"
        return lambda _: LineRunner(context, line, what,
                                    lambda: TimedDrive(line.linear_mps, line.angular_radps, line.duration_s))
    if isinstance(line, WaitLine):
        what = "wait" + (f" until {describe_condition(line.condition)}" if line.condition else "") + (
            f" {'at most ' if line.condition else ''}{line.duration_s:g} s" if line.duration_s else "")
        return lambda _: LineRunner(context, line, what,
                                    lambda: Wait(line.condition, line.duration_s, lambda: context.goal_reached))
    if isinstance(line, SetLine):
        return lambda _: LineRunner(context, line, f"set {line.setting} {line.value:g}",
                                    lambda: Instant(lambda: context.apply(line)))
    if isinstance(line, SayLine):
        return lambda _: LineRunner(context, line, "say", lambda: Instant(lambda: "said"), started_message=line.text)
    if isinstance(line, RepeatLine):
        body = block_steps(line.body, context)
        return lambda _: BlockLine(context, line, f"repeat {line.count}", lambda tick: ("", body * line.count))
    assert isinstance(line, IfLine) and line.condition is not None  # validation refuses an if without one
    condition, branches = line.condition, (line.then_block, line.else_block)

    def choose(tick: TickInput) -> tuple[str, list[tuple[str, StepFactory]]]:
        holds = condition_holds(condition, tick, context.goal_reached)
        return (": yes, then" if holds else ": no, else"), block_steps(branches[0] if holds else branches[1], context)

    return lambda _: BlockLine(context, line, f"if {describe_condition(condition)}", choose)


class PlanRunner(SkillController):
    """A whole plan as one motor goal: its top block, the plan's limits on the wheels, and its time cap."""

    def __init__(self, checked: CheckedPlan, registry: SkillRegistry, perception: Perception, spec: RobotSpec,
                 observer: PlanObserver | None = None, watchdog: DriveWatchdog | None = None) -> None:
        super().__init__()
        self._name = checked.plan.name
        self._context = PlanContext(registry, perception, spec, observer, watchdog)
        self._block = PlanBlock(block_steps(checked.plan.steps, self._context), self._context)
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
        self._context.give_back_watchdog()

    def position(self) -> str:
        """The line running now: a cancel, a preemption or a revoked control names it."""
        return f"line {self._context.line}" if self._context.line else ""
