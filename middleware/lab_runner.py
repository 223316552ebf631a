"""`telelab up`: the whole lab on one machine — skill servers as child processes, then the web tier."""

from __future__ import annotations

import os
import signal
import socket
import sys

from middleware.models import Role
from middleware.robots.processes import SkillServerProcess, SkillServerStartError

DEMO_ACCOUNTS = (("student", Role.STUDENT), ("tutor", Role.TUTOR), ("admin", Role.ADMIN))
# The teleoperation-under-delay experiment's robots (thesis chapter 4): one per course scene, idle until driven.
COURSE_ROBOTS = (("course-a", "course-A"), ("course-b", "course-B"))
MAX_WORKERS = 64


class PortTaken(RuntimeError):
    """The lab's port has a listener already: said before the robots start and the banner claims the lab runs."""


def check_port_free(host: str, port: int) -> None:
    """Binds host:port as gunicorn will (SO_REUSEADDR) and lets go; PortTaken when something listens there."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind((host, port))
        except OSError as error:
            raise PortTaken(f"Port {port} on {host} is in use ({error.strerror}): another Telelab, or another "
                            "server, listens there. Stop it, or choose another port with --port.") from None


class LabStopRequested(Exception):
    """SIGTERM (a service manager, `kill`) or SIGHUP (the terminal closed): stop as Ctrl-C does."""


def _request_stop(signum: int, _frame: object) -> None:
    signal.signal(signum, signal.SIG_IGN)  # a second signal must not cut the children's shutdown short
    raise LabStopRequested(signal.Signals(signum).name)


def stop_on_termination_signals() -> None:
    """Turns SIGTERM and SIGHUP into LabStopRequested in the main thread, so the skill servers are stopped
    instead of left running without their parent."""
    signal.signal(signal.SIGTERM, _request_stop)
    signal.signal(signal.SIGHUP, _request_stop)


def ensure_demo_accounts(app) -> list[tuple[str, str, str]]:
    """Creates the demo accounts that do not exist yet; returns (name, role, password) of the new ones."""
    from middleware.auth.services import create_user, find_user, generate_password
    from middleware.db import session_factory

    created = []
    with session_factory(app)() as session:
        for name, role in DEMO_ACCOUNTS:
            if find_user(session, name) is None:
                password = generate_password()
                create_user(session, name, role, password)
                created.append((name, role.value, password))
        session.commit()
    return created


def seed_demo_content(app, record_video: bool = True) -> list[str]:
    """The demo data: the demo course with its tests (so the demo student can book and be assessed) and its Spanish
    twin, then the teaching area's example tours and the lesson whose video is recorded from the simulator."""
    from middleware.analytics.demo import seed_demo_usage
    from middleware.recordings.demo import seed_demo_recording
    from middleware.teaching.demo_class import seed_demo_class
    from middleware.teaching.demo_content import seed_demo_content as seed

    return (seed_demo_course(app) + seed_spanish_demo_course(app) + seed(app, record_video) + seed_demo_recording(app)
            + seed_demo_class(app) + seed_demo_usage(app))


def seed_demo_course(app) -> list[str]:
    """The demo course "Mobile robotics (demo)" when it does not exist yet; returns what was added."""
    from middleware.db import session_factory
    from middleware.demo_course import seed_demo_course as seed

    with session_factory(app)() as session:
        added = seed(session).added
        session.commit()
    return added


def seed_spanish_demo_course(app) -> list[str]:
    """The demo course in Spanish, "Robótica móvil (demo)", when it does not exist yet (before the teaching area's
    content, whose Spanish lesson takes its tests); returns what was added."""
    from middleware.db import session_factory
    from middleware.demo_course import seed_spanish_demo_course as seed

    with session_factory(app)() as session:
        added = seed(session).added
        session.commit()
    return added


def lab_robots(robot_count: int, scene: str, course_robots: bool = True) -> list[SkillServerProcess]:
    """The skill servers `telelab up` runs: lab-1..lab-N in scene, then the experiment's course robots."""
    robots = [SkillServerProcess(f"lab-{i + 1}", scene) for i in range(robot_count)]
    if course_robots:
        robots += [SkillServerProcess(name, course_scene) for name, course_scene in COURSE_ROBOTS]
    return robots


def choose_farm(farm: str | None) -> None:
    """Sets TELELAB_FARM for the app; for a Ray farm with no TELELAB_RAY_ADDRESS, starts a local cluster."""
    if farm is None:
        return
    os.environ["TELELAB_FARM"] = farm
    if farm == "ray" and not os.environ.get("TELELAB_RAY_ADDRESS"):
        from middleware.farm.ray_farm import start_local_cluster

        try:
            os.environ["TELELAB_RAY_ADDRESS"] = start_local_cluster()
        except ImportError:
            raise SkillServerStartError("The Ray farm needs Ray: pip install 'telelab[ray]'.") from None
        print(f"robot farm: a local Ray cluster at {os.environ['TELELAB_RAY_ADDRESS']}", flush=True)


def choose_workers(database_url: str, workers: int | None) -> int:
    """How many web workers `telelab up` runs: one per core on PostgreSQL, one on SQLite (whose announcements
    stay inside one process, so a second worker would miss the first one's chat, queue and robot changes)."""
    on_sqlite = database_url.startswith("sqlite")
    if workers is None:
        return 1 if on_sqlite else max(1, os.cpu_count() or 1)
    if workers < 1 or workers > MAX_WORKERS:
        raise SkillServerStartError(f"--workers must be between 1 and {MAX_WORKERS}, not {workers}.")
    if workers > 1 and on_sqlite:
        raise SkillServerStartError("Several web workers need PostgreSQL, through which they hear each other's "
                                    "changes: set TELELAB_DATABASE_URL=postgresql://..., or use --workers 1.")
    return workers


def run_lab(host: str, port: int, robot_count: int, scene: str, course_robots: bool = True,
            farm: str | None = None, workers: int | None = None, demo_video: bool = True) -> int:
    """Starts skill servers and the farm, migrates the database, creates demo accounts, and serves with gunicorn
    until Ctrl-C or SIGTERM (SIGHUP restarts the web workers)."""
    from middleware import create_app
    from middleware.db import upgrade_to_head
    from middleware.farm.base import FarmUnavailable
    from middleware.farm.owner import FarmOwner
    from middleware.lti.demo_setup import DemoLmsProcess
    from middleware.serve import serve_with_gunicorn

    robots = lab_robots(robot_count, scene, course_robots)
    owner: FarmOwner | None = None
    demo_lms: DemoLmsProcess | None = None
    launcher = os.getpid()
    status = 0
    stop_on_termination_signals()
    try:
        check_port_free(host, port)
        choose_farm(farm)
        for robot in robots:
            robot.serve()
            print(f"robot {robot.name}: skill server at {robot.address} (scene {robot.scene})", flush=True)
        os.environ["TELELAB_ROBOTS"] = ",".join(f"{r.name}={r.address}" for r in robots)
        if os.environ.get("TELELAB_FARM", "local") == "local":  # the workers share one owner of the robots
            owner = FarmOwner()
            owner.start()
        app = create_app()
        worker_count = choose_workers(app.config["DATABASE_URL"], workers)
        upgrade_to_head(app.config["DATABASE_URL"])
        created = ensure_demo_accounts(app)
        seeded = seed_demo_content(app, demo_video)
        demo_lms, lms_seeded = start_demo_lms(app, host, port)
        _let_go(app)
        _print_banner(host, port, created, seeded + lms_seeded, worker_count, demo_lms.url if demo_lms else None)
        serve_with_gunicorn(host, port, worker_count)
    except (PortTaken, SkillServerStartError, FarmUnavailable) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, LabStopRequested, SystemExit) as stop:
        if os.getpid() != launcher:
            raise  # a gunicorn worker (a fork of this process) leaving: the lab, its robots and farm stay up
        status = stop.code if isinstance(stop, SystemExit) and isinstance(stop.code, int) else 0
        if status:  # gunicorn halted: its port was taken, or a worker could not boot (its log above says which)
            print(f"error: the web server stopped with status {status}; stopping the lab", file=sys.stderr,
                  flush=True)
        else:
            print("\nstopping the lab", flush=True)
    finally:
        if os.getpid() == launcher:
            if owner is not None:
                owner.stop()
            if demo_lms is not None:
                demo_lms.stop()
            for robot in robots:
                robot.stop()
    print("the lab has stopped", flush=True)
    return status


def start_demo_lms(app, host: str, port: int):
    """The demo LMS (a stand-in, for trying LTI) on the next port, registered and linked to the demo course;
    (its process or None when it could not start, what was added). The lab runs on without it."""
    from middleware.demo_course import DEMO_COURSE_CODE
    from middleware.lti.demo_setup import DemoLmsError, seed_demo_lms
    from middleware.lti.demo_setup import start_demo_lms as start

    tool_host = "127.0.0.1" if host in ("0.0.0.0", "::", "") else host
    try:
        lms = start(app, f"http://{tool_host}:{port}", port + 1)
    except DemoLmsError as error:
        print(f"warning: {error}", file=sys.stderr)
        return None, []
    return lms, seed_demo_lms(app, lms.url, DEMO_COURSE_CODE)


def _let_go(app) -> None:
    """The launcher's own app has done its set-up: its connections and threads must not be forked into workers."""
    from middleware.access.coordinator import access_coordinator
    from middleware.db import session_factory
    from middleware.farm.setup import robot_farm
    from middleware.robots.registry import robot_registry

    access_coordinator(app).close()
    robot_registry(app).close()
    robot_farm(app).close()
    session_factory(app).kw["bind"].dispose()


def _print_banner(host: str, port: int, created: list[tuple[str, str, str]], seeded: list[str] | None = None,
                  workers: int = 1, lms_url: str | None = None) -> None:
    served_by = f"{workers} web worker{'s' if workers > 1 else ''}"
    lines = ["", f"Telelab is running at http://{host}:{port} with {served_by}  (Ctrl-C stops it)"]
    if seeded:
        lines.append("Demo data added: " + "; ".join(seeded) + ".")
    if created:
        lines.append("Demo accounts (the passwords are shown only this once; "
                     "change one with `telelab users set-password NAME`):")
        lines += [f"  {role:8} {name:10} password: {password}" for name, role, password in created]
    else:
        lines.append("The demo accounts student, tutor and admin exist already; "
                     "`telelab users set-password NAME` gives one a new password.")
    if lms_url:
        lines.append(f"Demo LMS (a stand-in for Moodle or Canvas, to try LTI): {lms_url}  (its learner and "
                     "instructor open Telelab from its course page; docs/lti.md)")
    print("\n".join(lines) + "\n", flush=True)
