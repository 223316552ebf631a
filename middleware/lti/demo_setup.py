"""The demo LMS beside `telelab up`: started as a child process on its own port, registered as a platform in the
demo data, and its course linked to the demo course (so its instructor places the demo course's tests and its
learner takes them). `lab_runner` calls these; the LMS itself is `demo_lms.py`.
"""

from __future__ import annotations

import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path

from flask import Flask
from sqlalchemy import select

from middleware.db import session_factory
from middleware.lti import demo_lms, keys, platforms
from middleware.lti.demo_platform import registration
from middleware.models import Course
from middleware.models.lti import LtiContext, LtiPlatform

DEMO_LMS_NAME = "Demo LMS (a stand-in)"
START_TIMEOUT_S = 30.0
STATE_FILE = "demo-lms.json"


class DemoLmsError(RuntimeError):
    """The demo LMS did not start (the lab runs on without it)."""


class DemoLmsProcess:
    """The demo LMS as a child process; it exits with this process even when this one is killed."""

    def __init__(self, tool_url: str, state_path: Path, port: int) -> None:
        self.tool_url, self.state_path, self.port = tool_url, state_path, port
        self.process: subprocess.Popen[str] | None = None
        self._drain: threading.Thread | None = None
        self.url = ""

    def start(self) -> str:
        """Starts it and waits for the line that gives its address; its address."""
        command = [sys.executable, "-m", "middleware.lti.demo_lms", "--port", str(self.port), "--tool", self.tool_url,
                   "--state", str(self.state_path), "--parent-pid", str(os.getpid())]
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        lines: queue.Queue[str] = queue.Queue()

        def drain(stream) -> None:  # the first line to the waiter, the rest dropped (a full pipe would block it)
            for line in stream:
                lines.put(line)

        self._drain = threading.Thread(target=drain, args=(self.process.stdout,), name="demo-lms-output", daemon=True)
        self._drain.start()
        seen: list[str] = []
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline:
            try:
                line = lines.get(timeout=0.1)
            except queue.Empty:
                if self.process.poll() is not None and lines.empty():
                    break  # it ended (its port taken, say): no need to wait for the deadline
                continue
            seen.append(line)
            if line.startswith(demo_lms.READY_LINE):
                self.url = line.removeprefix(demo_lms.READY_LINE).strip()
                return self.url
        self.stop()
        raise DemoLmsError("the demo LMS did not start: " + " ".join(seen)[-500:])

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stops it (SIGTERM, then SIGKILL)."""
        if self.process is None:
            return
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout_s)
        if self._drain is not None:
            self._drain.join(timeout_s)  # it ends at the pipe's end, which the process's exit gives
        if self.process.stdout is not None:
            self.process.stdout.close()


def start_demo_lms(app: Flask, tool_url: str, port: int) -> DemoLmsProcess:
    """The demo LMS on 127.0.0.1:port, or on a free port when that one is taken."""
    state = Path(app.instance_path) / STATE_FILE
    lms = DemoLmsProcess(tool_url, state, port)
    try:
        lms.start()
    except DemoLmsError:
        lms = DemoLmsProcess(tool_url, state, 0)
        lms.start()
    return lms


def seed_demo_lms(app: Flask, lms_url: str, course_code: str) -> list[str]:
    """Registers the demo LMS at lms_url (again, if its address changed) and links its course to the Telelab course
    of course_code (the demo course) once; returns what was added."""
    fields = registration(DEMO_LMS_NAME, lms_url, demo_lms.CLIENT_ID, demo_lms.DEPLOYMENT_ID)
    added = []
    with session_factory(app)() as session, session.begin():
        known = session.scalar(select(LtiPlatform.id).where(LtiPlatform.issuer == lms_url,
                                                            LtiPlatform.client_id == demo_lms.CLIENT_ID))
        platform = platforms.register(session, fields)
        keys.signing_key(session)
        if known is None:
            added.append(f"the demo LMS registered as an LTI platform ({lms_url})")
        course_id = session.scalar(select(Course.id).where(Course.code == course_code))
        linked = session.scalar(select(LtiContext.id).where(LtiContext.issuer == lms_url,
                                                            LtiContext.context_id == demo_lms.COURSE.id))
        if course_id is not None and linked is None:
            session.add(LtiContext(platform_id=platform.id, issuer=lms_url, context_id=demo_lms.COURSE.id,
                                   course_id=course_id, ags_scopes=[]))
            added.append("its course linked to the demo course")
    return added
