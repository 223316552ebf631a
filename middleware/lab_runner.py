"""`telelab up`: the whole lab on one machine — skill servers as child processes, then the web tier."""

from __future__ import annotations

import os
import signal
import sys

from middleware.models import Role
from middleware.robots.processes import SkillServerProcess, SkillServerStartError

DEMO_ACCOUNTS = (("student", Role.STUDENT), ("tutor", Role.TUTOR), ("admin", Role.ADMIN))
# The teleoperation-under-delay experiment's robots (thesis chapter 4): one per course scene, idle until driven.
COURSE_ROBOTS = (("course-a", "course-A"), ("course-b", "course-B"))


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


def seed_demo_content(app) -> list[str]:
    """The demo data: the demo course with its tests (so the demo student can book and be assessed), then the
    teaching area's example tours and the lesson whose video is recorded from the simulator."""
    from middleware.teaching.demo_content import seed_demo_content as seed

    return seed_demo_course(app) + seed(app)


def seed_demo_course(app) -> list[str]:
    """The demo course "Mobile robotics (demo)" when it does not exist yet; returns what was added."""
    from middleware.db import session_factory
    from middleware.demo_course import seed_demo_course as seed

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


def run_lab(host: str, port: int, robot_count: int, scene: str, course_robots: bool = True,
            farm: str | None = None) -> int:
    """Starts skill servers, migrates the database, creates demo accounts, and serves until Ctrl-C or SIGTERM."""
    from middleware import create_app
    from middleware.db import upgrade_to_head
    from middleware.serve import serve_forever

    robots = lab_robots(robot_count, scene, course_robots)
    stop_on_termination_signals()
    try:
        choose_farm(farm)
        for robot in robots:
            robot.serve()
            print(f"robot {robot.name}: skill server at {robot.address} (scene {robot.scene})", flush=True)
        os.environ["TELELAB_ROBOTS"] = ",".join(f"{r.name}={r.address}" for r in robots)
        app = create_app()
        upgrade_to_head(app.config["DATABASE_URL"])
        created = ensure_demo_accounts(app)
        seeded = seed_demo_content(app)
        _print_banner(host, port, created, seeded)
        serve_forever(app, host, port)
    except SkillServerStartError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, LabStopRequested):
        print("\nstopping the lab", flush=True)
    finally:
        for robot in robots:
            robot.stop()
    print("the lab has stopped", flush=True)
    return 0


def _print_banner(host: str, port: int, created: list[tuple[str, str, str]], seeded: list[str] | None = None) -> None:
    lines = ["", f"Telelab is running at http://{host}:{port}  (Ctrl-C stops it)"]
    if seeded:
        lines.append("Demo data added: " + "; ".join(seeded) + ".")
    if created:
        lines.append("Demo accounts (the passwords are shown only this once; "
                     "change one with `telelab users set-password NAME`):")
        lines += [f"  {role:8} {name:10} password: {password}" for name, role, password in created]
    else:
        lines.append("The demo accounts student, tutor and admin exist already; "
                     "`telelab users set-password NAME` gives one a new password.")
    print("\n".join(lines) + "\n", flush=True)
