"""The app's recorder parts in a worker: the command notes and the keeper (the writer child does the rest, and
imports none of this)."""


from __future__ import annotations

from flask import Flask

from middleware.access.commands import CommandNote, robot_commands
from middleware.db import session_factory
from middleware.recordings import settings as recording_settings
from middleware.recordings.command_log import CommandSink
from middleware.recordings.recorder import RecordingKeeper
from middleware.robots.registry import robot_registry

_KEY = "telelab.recordings"


class Recordings:
    """The app's recorder parts: the command notes and the keeper every worker has (writer child: the rest)."""

    def __init__(self, app: Flask) -> None:
        self._app = app
        self.sink = CommandSink()
        self._keeper: RecordingKeeper | None = None
        self._active: bool | None = None

    @property
    def active(self) -> bool:
        """Whether this app records (decided on first use: tests configure the app after create_app)."""
        if self._active is None:
            self._active = enabled(self._app)
        return self._active

    def observe(self, note: CommandNote) -> None:
        """The command path's observer: queues the note when recording is on."""
        if self.active:
            self.sink.observe(note)

    @property
    def settings(self) -> recording_settings.RecordingSettings:
        """The settings (read when first needed: tests set the instance path after create_app)."""
        return self.keeper.settings

    @property
    def keeper(self) -> RecordingKeeper:
        """The keeper (made once, not started)."""
        if self._keeper is None:
            self._keeper = RecordingKeeper(self._app, session_factory(self._app), robot_registry(self._app),
                                           recording_settings.load(self._app), self.sink)
        return self._keeper

    def stop(self) -> None:
        """Stops the keeper, which hands its last notes and seconds to its writer child (tests, shut-down)."""
        if self._keeper is not None:
            self._keeper.stop()


def enabled(app: Flask) -> bool:
    """Whether this app records: by default yes, except in tests, which turn it on with RECORDINGS_ENABLED."""
    if "RECORDINGS_ENABLED" in app.config:
        return recording_settings.load(app).enabled
    return not app.config.get("TESTING") and recording_settings.load(app).enabled


def init_app(app: Flask) -> None:
    """Hands the command path its observer and starts the keeper with the first request (every worker runs one;
    the elected one records)."""
    recordings = app.extensions[_KEY] = Recordings(app)
    robot_commands(app).observe(recordings.observe)

    @app.before_request
    def _start_keeper() -> None:
        if recordings.active:
            recordings.keeper.start()


def recordings_of(app: Flask) -> Recordings:
    """The app's recorder parts."""
    return app.extensions[_KEY]
