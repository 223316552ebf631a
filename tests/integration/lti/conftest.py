"""A served Telelab and a test LMS registered with it (module-scoped: one app and one platform per file)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlencode, urlsplit

import pytest

from tests.conftest import LabClient, LiveServer, _let_go, make_test_app
from tests.integration.lti.platform import LmsPlatform


@pytest.fixture(scope="module")
def tool(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    """Telelab on a fresh SQLite database, no robots, served."""
    tmp = tmp_path_factory.mktemp("lti")
    app = make_test_app(f"sqlite:///{tmp / 'lti.sqlite3'}", "", Path(tmp))
    server = LiveServer(app)
    yield server
    server.stop()
    _let_go(app)
    from middleware.lti.setup import _SENDER_KEY

    app.extensions[_SENDER_KEY].stop()


def register(tool: LiveServer, platform: LmsPlatform) -> None:
    """Registers platform with the tool as an admin would."""
    from middleware.db import unit_of_work
    from middleware.lti import platforms

    with tool.app.app_context(), unit_of_work(tool.app) as session:
        platforms.register(session, dict(platform.registration()))


@pytest.fixture(scope="module")
def lms(tool: LiveServer) -> Iterator[LmsPlatform]:
    """The test LMS, registered."""
    platform = LmsPlatform(tool_url=tool.url)
    register(tool, platform)
    yield platform
    platform.stop()


def begin_login(client: LabClient, platform: LmsPlatform, hint: str = "hint") -> tuple[str, str]:
    """The OIDC login initiation as the LMS sends it; (nonce, state) from the redirect to the LMS."""
    params = {"iss": platform.issuer, "login_hint": hint, "client_id": platform.client_id,
              "lti_deployment_id": platform.deployment_id, "target_link_uri": platform.tool_url + "/lti/launch",
              "telelab_checked": "1"}
    status, headers, body = client.request("GET", "/lti/login?" + urlencode(params))
    assert status == 302, body
    query = parse_qs(urlsplit(headers["Location"]).query)
    assert headers["Location"].startswith(platform.url + "/auth?")
    return query["nonce"][0], query["state"][0]


def launch(client: LabClient, platform: LmsPlatform, sub: str, roles: list[str],
           signer: LmsPlatform | None = None, change: dict[str, Any] | None = None,
           drop: tuple[str, ...] = (), **kwargs: Any) -> tuple[int, dict[str, str], str]:
    """A whole launch (login, the LMS's signed id token, the post); (status, headers, body) of the post."""
    nonce, state = begin_login(client, platform)
    claims = platform.claims(nonce, sub, roles, **kwargs)
    claims.update(change or {})
    for name in drop:
        claims.pop(name, None)
    token = (signer or platform).sign(claims)
    return client.request("POST", "/lti/launch", {"id_token": token, "state": state})
