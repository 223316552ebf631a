"""The `telelab` command: run the lab, its tiers, migrations and accounts."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from middleware.auth.schemas import InvalidField
from middleware.errors import Refused
from middleware.lti import commands as lti_commands


def _app(**overrides: object):
    from middleware import create_app

    return create_app(dict(overrides) or None)


def cmd_db_upgrade(_args: argparse.Namespace) -> int:
    """Migrates the configured database to the newest revision."""
    from middleware.db import upgrade_to_head

    app = _app()
    upgrade_to_head(app.config["DATABASE_URL"])
    print(f"database at {_redacted(app.config['DATABASE_URL'])} is at the newest revision")
    return 0


def _read_password(args: argparse.Namespace) -> tuple[str, bool]:
    """The password from stdin when it is not a terminal, else a generated one; and whether generated."""
    from middleware.auth.services import generate_password

    if args.generate or sys.stdin.isatty():
        return generate_password(), True
    return sys.stdin.readline().rstrip("\n"), False


def cmd_users_add(args: argparse.Namespace) -> int:
    """Creates an account; prints a generated password once."""
    from middleware.auth.services import AccountExists, create_user
    from middleware.db import session_factory

    password, generated = _read_password(args)
    app = _app()
    with session_factory(app)() as session:
        try:
            user = create_user(session, args.name, args.role, password)
            session.commit()
        except (InvalidField, AccountExists) as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
    print(f"created {user.role} {user.username}" + (f" with password {password}" if generated else ""))
    return 0


def cmd_users_set_password(args: argparse.Namespace) -> int:
    """Replaces an account's password; prints a generated one once."""
    from middleware.auth.services import set_password
    from middleware.db import session_factory

    password, generated = _read_password(args)
    app = _app()
    with session_factory(app)() as session:
        try:
            user = set_password(session, args.name, password)
            session.commit()
        except InvalidField as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
    print(f"password of {user.username} changed" + (f" to {password}" if generated else ""))
    return 0


def cmd_users_set_active(args: argparse.Namespace) -> int:
    """Disables or enables an account; a disabled user's session stops working at the next request."""
    from middleware.accounts.services import set_active_by_name
    from middleware.db import session_factory

    with session_factory(_app())() as session:
        try:
            user = set_active_by_name(session, args.name, args.active)
            session.commit()
        except InvalidField as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
    print(f"{user.username} is {'enabled' if user.is_active else 'disabled'}")
    return 0


def cmd_users_list(_args: argparse.Namespace) -> int:
    """Lists the accounts."""
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import User

    with session_factory(_app())() as session:
        for user in session.scalars(select(User).order_by(User.username)):
            print(f"{user.username:24} {user.role:8} {'active' if user.is_active else 'disabled'}")
    return 0


def cmd_web(args: argparse.Namespace) -> int:
    """Serves the middleware on Werkzeug's threaded server (an open WebSocket holds no thread: live/loop.py)."""
    from middleware.serve import serve_forever

    serve_forever(_app(), args.host, args.port)
    return 0


def cmd_skill_server(args: argparse.Namespace) -> int:
    """Runs one robot's skill server (the skill_server package, in this same interpreter)."""
    # The tiers meet only over gRPC, so the middleware starts the robot tier as a program, never imports it.
    argv = [sys.executable, "-m", "skill_server", *args.skill_server_args]
    os.execv(sys.executable, argv)
    return 1  # not reached


def cmd_up(args: argparse.Namespace) -> int:
    """Starts the whole lab on this machine."""
    from middleware.lab_runner import run_lab

    return run_lab(host=args.host, port=args.port, robot_count=args.robots, scene=args.scene,
                   course_robots=args.course_robots, farm=args.farm, workers=args.workers,
                   demo_video=args.demo_video)


def _farm_and_app():
    from middleware.farm.setup import robot_farm

    app = _app()
    return robot_farm(app), app


def cmd_farm_status(_args: argparse.Namespace) -> int:
    """Prints the farm's hosts, capacity and robots with their load."""
    from middleware.db import session_factory
    from middleware.farm.report import status_lines

    farm, app = _farm_and_app()
    print("\n".join(status_lines(farm, session_factory(app))))
    return 0


def _local_farm_refused(farm, page: str) -> bool:
    if farm.backend != "local":
        return False
    print(f"error: with the local farm, robots are children of the web server; use its page {page} "
          "(or the Ray farm, TELELAB_FARM=ray)", file=sys.stderr)
    return True


def cmd_farm_start(args: argparse.Namespace) -> int:
    """Starts simulated robots of a pool on the farm (they join the lab as robots of the kind)."""
    from middleware.db import session_factory
    from middleware.farm.pool_robots import clean_pool_request, start_pool_robots

    farm, app = _farm_and_app()
    if _local_farm_refused(farm, "/admin/pools"):
        return 1
    kind, scene, count = clean_pool_request(args.pool, args.scene, args.count)
    with session_factory(app)() as session, session.begin():
        started = start_pool_robots(farm, session, kind, scene, count)
    print(f"started {', '.join(started)} (kind {kind}, scene {scene})")
    return 0


def cmd_farm_stop(args: argparse.Namespace) -> int:
    """Stops one robot of the farm (a practice robot's owner sees it stopped), or a pool's robots."""
    from middleware.db import session_factory
    from middleware.farm.pool_robots import stop_pool_robots
    from middleware.teaching.practice_robots import practice_manager

    farm, app = _farm_and_app()
    if _local_farm_refused(farm, "/admin/pools" if args.pool else "/admin/farm"):
        return 1
    if args.pool:
        print(f"stopped {', '.join(stop_pool_robots(farm, session_factory(app), args.pool))}")
        return 0
    if not args.name:
        print("error: name a robot, or a pool with --pool KIND", file=sys.stderr)
        return 2
    if practice_manager(app).stop_named(args.name) or farm.stop(args.name):
        print(f"stopped {args.name}")
        return 0
    print(f"error: the farm runs no robot called {args.name}", file=sys.stderr)
    return 1


def cmd_farm_drain(args: argparse.Namespace) -> int:
    """Moves every robot off a Ray node and keeps new ones off it."""
    farm, _app_ = _farm_and_app()
    drain = getattr(farm, "drain", None)
    if drain is None:
        print("error: only the Ray farm has hosts to drain (TELELAB_FARM=ray)", file=sys.stderr)
        return 1
    moved = drain(args.node)
    print(f"drained {args.node}: moved {', '.join(moved) if moved else 'no robot'}")
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    """Runs the benchmarks (they start their own lab on loopback)."""
    import subprocess

    command = [sys.executable, "-m", "benchmarks", "--output", args.output] + (["--quick"] if args.quick else [])
    return subprocess.run(command, check=False).returncode


def _redacted(url: str) -> str:
    scheme, sep, rest = url.partition("://")
    if "@" in rest:
        rest = "***@" + rest.split("@", 1)[1]
    return scheme + sep + rest


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of `telelab`."""
    parser = argparse.ArgumentParser(prog="telelab", description="Telelab, a remote laboratory for mobile robotics.")
    commands = parser.add_subparsers(dest="command", required=True)

    up = commands.add_parser("up", help="start the whole lab: skill server(s), database, web")
    up.add_argument("--host", default="127.0.0.1")
    up.add_argument("--port", type=int, default=5000)
    up.add_argument("--robots", type=int, default=2,
                    help="how many simulated lab robots (default 2: a pool of lab robots, so students may queue for "
                         "any of them)")
    up.add_argument("--scene", default="lab", help="scene of the simulated robots (default lab)")
    up.add_argument("--no-course-robots", dest="course_robots", action="store_false",
                    help="do not start the experiment's robots course-a and course-b")
    up.add_argument("--farm", choices=["local", "ray"], default=None,
                    help="where practice robots run: child processes (local, the default) or a Ray cluster; "
                         "ray starts one on 127.0.0.1 unless TELELAB_RAY_ADDRESS names one")
    up.add_argument("--workers", type=int, default=None,
                    help="web workers (gunicorn) on the one port: default one per core with PostgreSQL, "
                         "1 with the embedded SQLite database")
    up.add_argument("--no-demo-video", dest="demo_video", action="store_false",
                    help="do not record the demo lesson's video (its lesson is added once the video exists)")
    up.set_defaults(handler=cmd_up)

    web = commands.add_parser("web", help="serve the middleware only (robots from TELELAB_ROBOTS)")
    web.add_argument("--host", default="127.0.0.1")
    web.add_argument("--port", type=int, default=5000)
    web.set_defaults(handler=cmd_web)

    skill = commands.add_parser("skill-server", help="run one robot's skill server", add_help=False)
    skill.add_argument("skill_server_args", nargs=argparse.REMAINDER,
                       help="--port P [--host H] [--scene NAME] [--seed N] [--fast] [--name ROBOT]")
    skill.set_defaults(handler=cmd_skill_server)

    database = commands.add_parser("db", help="database maintenance")
    db_commands = database.add_subparsers(dest="db_command", required=True)
    db_commands.add_parser("upgrade", help="migrate to the newest revision").set_defaults(handler=cmd_db_upgrade)

    users = commands.add_parser("users", help="accounts")
    user_commands = users.add_subparsers(dest="users_command", required=True)
    add = user_commands.add_parser("add", help="create an account (password from stdin, or generated)")
    add.add_argument("name")
    add.add_argument("--role", required=True, choices=["student", "tutor", "admin"])
    add.add_argument("--generate", action="store_true", help="generate the password even if stdin is a pipe")
    add.set_defaults(handler=cmd_users_add)
    reset = user_commands.add_parser("set-password", help="replace a password (from stdin, or generated)")
    reset.add_argument("name")
    reset.add_argument("--generate", action="store_true")
    reset.set_defaults(handler=cmd_users_set_password)
    user_commands.add_parser("list", help="list the accounts").set_defaults(handler=cmd_users_list)
    disable = user_commands.add_parser("disable", help="disable an account (its sessions end)")
    disable.add_argument("name")
    disable.set_defaults(handler=cmd_users_set_active, active=False)
    enable = user_commands.add_parser("enable", help="enable a disabled account")
    enable.add_argument("name")
    enable.set_defaults(handler=cmd_users_set_active, active=True)

    farm = commands.add_parser("farm", help="the robot farm: status, start or stop a pool's robots, drain a host")
    farm_commands = farm.add_subparsers(dest="farm_command", required=True)
    farm_commands.add_parser("status", help="hosts, capacity, robots and their load").set_defaults(
        handler=cmd_farm_status)
    start = farm_commands.add_parser("start", help="start simulated robots of a pool (named KIND-1, KIND-2...)")
    start.add_argument("--pool", required=True, metavar="KIND", help="the robots' kind (their pool)")
    start.add_argument("--scene", default="lab", help="the simulator scene they run (default lab)")
    start.add_argument("--count", default="1", help="how many to add (1-50, default 1)")
    start.set_defaults(handler=cmd_farm_start)
    stop = farm_commands.add_parser("stop", help="stop one robot, or every farm robot of a pool")
    stop.add_argument("name", nargs="?")
    stop.add_argument("--pool", metavar="KIND", help="stop the farm's robots of this kind")
    stop.set_defaults(handler=cmd_farm_stop)
    drain = farm_commands.add_parser("drain", help="move every robot off a Ray node (its id from status)")
    drain.add_argument("node")
    drain.set_defaults(handler=cmd_farm_drain)

    lti_commands.add_commands(commands, _app)  # telelab lti register | urls | list | rotate-key | retire-key

    bench = commands.add_parser("bench", help="measure response times, streaming and capacity")
    bench.add_argument("--quick", action="store_true", help="a short smoke run that asserts no timings")
    bench.add_argument("--output", default="bench-results", help="folder for the JSON and histograms")
    bench.set_defaults(handler=cmd_bench)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `telelab` console script."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["skill-server"] and not {"-h", "--help"} & set(argv[1:2]):
        # Every flag belongs to the skill server; argparse would try to claim them.
        return cmd_skill_server(argparse.Namespace(skill_server_args=argv[1:]))
    args = build_parser().parse_args(argv)
    try:
        return int(args.handler(args))
    except Refused as refusal:  # the farm unreachable, a node unknown: the sentence, not a traceback
        print(f"error: {refusal.message}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
