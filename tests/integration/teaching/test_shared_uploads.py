"""Lesson videos live where every web host reads them: with TELELAB_SHARED_DIR set, a video uploaded through one
host is listed and served by another (two apps, each with an instance folder of its own, on one database)."""

from __future__ import annotations

import io
from pathlib import Path
from urllib.request import Request

from middleware import create_app
from middleware.config import ConfigError, shared_dir
from middleware.teaching.lesson_uploads import store_video
from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, _let_go, add_test_account, make_test_app
from tests.integration.teaching.test_practice_console_and_uploads import WEBM_HEAD


def test_a_video_uploaded_on_one_host_is_served_by_another(tmp_path: Path, skill_server_address: str) -> None:
    database_url = f"sqlite:///{tmp_path / 'shared.sqlite3'}"
    robots = f"lab-1={skill_server_address}"
    first = make_test_app(database_url, robots, tmp_path / "host-a")
    second = create_app({"DATABASE_URL": database_url, "SECRET_KEY": first.config["SECRET_KEY"], "TESTING": True})
    second.instance_path = str(tmp_path / "host-b" / "instance")
    from middleware.db import session_factory

    with session_factory(first)() as session:
        add_test_account(session, "tutor1", "tutor")
        session.commit()
    for app in (first, second):
        app.config["SHARED_DIR"] = tmp_path / "shared"
    hosts = [LiveServer(first), LiveServer(second)]
    try:
        viewer = LabClient(hosts[1].url)
        assert viewer.login("tutor1", STUDENT_PASSWORD) == 302
        with first.app_context():  # what host A's upload route calls with the upload's stream
            name = store_video(first.instance_path, "clip.webm", io.BytesIO(WEBM_HEAD + b"on host a"), 10_000)
        status, _, editor = viewer.request("GET", "/lessons/new")
        assert status == 200 and name in editor, "host B's lesson editor offers the video uploaded on host A"
        assert (tmp_path / "shared" / "lessons" / name).is_file()
        assert not (Path(first.instance_path) / "lessons").exists(), "not on the uploading host's own disk"
        with viewer._opener.open(Request(f"{viewer.base_url}/lessons/videos/{name}"), timeout=10) as response:
            assert response.status == 200 and response.read() == WEBM_HEAD + b"on host a"
    finally:
        for host in hosts:
            host.stop()
            _let_go(host.app)


def test_the_shared_folder_must_be_absolute() -> None:
    assert shared_dir({}) is None
    assert shared_dir({"TELELAB_SHARED_DIR": "/srv/telelab"}) == Path("/srv/telelab")
    try:
        shared_dir({"TELELAB_SHARED_DIR": "relative/dir"})
    except ConfigError as refused:
        assert "TELELAB_SHARED_DIR" in str(refused)
    else:
        raise AssertionError("a relative folder is refused")
