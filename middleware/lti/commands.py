"""`telelab lti ...`: register a platform and print what its administrator pastes; list; rotate or retire keys.

Each command is a unit of work of its own (`with sessions() as s, s.begin()`), like the other console commands.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from functools import partial

from flask import Flask

from middleware.db import session_factory
from middleware.errors import Refused
from middleware.lti import keys, platforms


def add_commands(commands: argparse._SubParsersAction, make_app: Callable[[], Flask]) -> None:
    """Adds `telelab lti` and its subcommands to the `telelab` parser; make_app builds the app a command needs."""
    lti = commands.add_parser("lti", help="LTI 1.3: LMS platforms and the tool's keys")
    lti_commands = lti.add_subparsers(dest="lti_command", required=True)
    register = lti_commands.add_parser("register", help="register an LMS and print what its administrator pastes")
    register.add_argument("--name", default="")
    register.add_argument("--issuer", required=True, help="the platform id (Moodle: its site URL)")
    register.add_argument("--client-id", required=True)
    register.add_argument("--deployment-id", required=True, action="append", dest="deployment_ids",
                          help="repeat for several deployments")
    register.add_argument("--auth-login-url", required=True, help="the LMS's OIDC authentication request URL")
    register.add_argument("--auth-token-url", required=True, help="the LMS's access token URL")
    register.add_argument("--key-set-url", required=True, help="the LMS's public keyset (JWKS) URL")
    register.add_argument("--frame-origin", action="append", dest="frame_origins", default=[],
                          help="another origin of the LMS's pages that frames Telelab (Canvas: the school's site)")
    register.add_argument("--site", default="http://127.0.0.1:5000",
                          help="Telelab's public address, for the URLs printed (default http://127.0.0.1:5000)")
    register.set_defaults(handler=partial(cmd_register, make_app))
    urls = lti_commands.add_parser("urls", help="print what an LMS's administrator pastes, without registering")
    urls.add_argument("--site", default="http://127.0.0.1:5000")
    urls.set_defaults(handler=partial(cmd_urls, make_app))
    lti_commands.add_parser("list", help="the registered platforms").set_defaults(handler=partial(cmd_list, make_app))
    lti_commands.add_parser("rotate-key", help="a new signing key (the old one stays published until retired)") \
        .set_defaults(handler=partial(cmd_rotate, make_app))
    retire = lti_commands.add_parser("retire-key", help="take an old key out of the JWKS")
    retire.add_argument("kid")
    retire.set_defaults(handler=partial(cmd_retire, make_app))


def _print_urls(site: str) -> None:
    urls = platforms.tool_urls(site)
    print("Paste in the LMS (Moodle: Site administration > Plugins > External tool > Manage tools > configure a "
          "tool manually, LTI 1.3; Canvas: Developer Keys > + LTI Key):")
    print(f"  Tool URL:                      {urls['tool_url']}")
    print(f"  Initiate login URL:            {urls['login_url']}")
    print(f"  Redirection / target link URI: {urls['launch_url']}")
    print(f"  Content selection (deep link): {urls['deep_link_url']}")
    print(f"  Public keyset (JWKS) URL:      {urls['jwks_url']}")
    print("  Services: IMS LTI Assignment and Grade Services, Names and Role Provisioning; send names: yes")


def cmd_register(make_app: Callable[[], Flask], args: argparse.Namespace) -> int:
    """Registers (or updates) a platform and prints the tool's URLs and the client id."""
    fields = {"name": args.name, "issuer": args.issuer, "client_id": args.client_id,
              "deployment_ids": args.deployment_ids, "auth_login_url": args.auth_login_url,
              "auth_token_url": args.auth_token_url, "key_set_url": args.key_set_url,
              "frame_origins": args.frame_origins}
    try:
        platforms.clean_platform(fields)  # a wrong field is named before the app starts
        app = make_app()
        with app.app_context(), session_factory(app)() as session, session.begin():
            platform = platforms.register(session, fields)
            keys.signing_key(session)
            name, client_id = platform.name, platform.client_id
    except Refused as refused:
        print(f"error: {refused.field}: {refused.message}", file=sys.stderr)
        return 2
    print(f"registered {name} (client id {client_id})")
    _print_urls(args.site)
    return 0


def cmd_urls(_make_app: Callable[[], Flask], args: argparse.Namespace) -> int:
    """Prints the tool's URLs for site."""
    _print_urls(args.site)
    return 0


def cmd_list(make_app: Callable[[], Flask], _args: argparse.Namespace) -> int:
    """Prints every registered platform."""
    app = make_app()
    with session_factory(app)() as session:
        for platform, deployments in platforms.listed(session):
            print(f"{platform.id}\t{platform.name}\t{platform.issuer}\tclient {platform.client_id}\t"
                  f"deployments {', '.join(deployments)}")
    return 0


def cmd_rotate(make_app: Callable[[], Flask], _args: argparse.Namespace) -> int:
    """Makes a new signing key."""
    app = make_app()
    with session_factory(app)() as session, session.begin():
        kid = keys.rotate(session).kid
    print(f"new signing key {kid}; the previous keys stay in the JWKS until retired")
    return 0


def cmd_retire(make_app: Callable[[], Flask], args: argparse.Namespace) -> int:
    """Retires an old key."""
    app = make_app()
    try:
        with session_factory(app)() as session, session.begin():
            keys.retire(session, args.kid)
    except Refused as refused:
        print(f"error: {refused.message}", file=sys.stderr)
        return 2
    print(f"retired {args.kid}")
    return 0
