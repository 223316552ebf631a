"""The event manager of the 2003 paper's skills: the events every goal announced in this tick, for the skills and
plans that react to another's events (a plan's `on localized` hears the localization goal running beside it).

Ticked in the world's loop thread only: the sequencer starts each tick afresh and publishes each goal's events as
the goal is ticked (pose estimators and perceptive skills before the motor goal, so a plan hears them the same tick).
"""

from __future__ import annotations

from dataclasses import dataclass

from skill_server.goals import EventKind

MAX_EVENTS_PER_TICK = 200  # a runaway skill cannot grow a tick's list without bound


@dataclass(frozen=True)
class PublishedEvent:
    """One event of a goal: the skill that announced it, its kind and its sentence, at sim_time_s."""

    sim_time_s: float
    skill: str
    kind: EventKind
    message: str


class EventManager:
    """The events of the current tick, published by the goals and read by whoever registered interest."""

    def __init__(self) -> None:
        self._sim_time_s = 0.0
        self._events: list[PublishedEvent] = []

    def new_tick(self, sim_time_s: float) -> None:
        """A tick begins: the previous tick's events are forgotten."""
        self._sim_time_s, self._events = sim_time_s, []

    def publish(self, skill: str, kind: EventKind, message: str) -> None:
        """A goal of skill announced an event."""
        if len(self._events) < MAX_EVENTS_PER_TICK:
            self._events.append(PublishedEvent(self._sim_time_s, skill, kind, message))

    def published(self) -> tuple[PublishedEvent, ...]:
        """The events published so far in this tick, in order."""
        return tuple(self._events)
