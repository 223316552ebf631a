"""`telelab lti register` registers an LMS and prints what its administrator pastes; a wrong field is named."""

from __future__ import annotations

from pathlib import Path

import pytest

from middleware.cli import main
from tests.conftest import _let_go, make_test_app, migrate_to_head


def test_register_prints_what_the_lms_admin_pastes_and_names_a_wrong_field(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    url = f"sqlite:///{tmp_path / 'cli.sqlite3'}"
    migrate_to_head(url)
    monkeypatch.setenv("TELELAB_DATABASE_URL", url)
    moodle = "https://moodle.example.edu"
    args = ["lti", "register", "--issuer", moodle, "--client-id", "abc123", "--deployment-id", "1",
            "--auth-login-url", moodle + "/mod/lti/auth.php", "--auth-token-url", moodle + "/mod/lti/token.php",
            "--key-set-url", moodle + "/mod/lti/certs.php", "--site", "https://telelab.example.edu"]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "registered moodle.example.edu (client id abc123)" in printed
    assert "Initiate login URL:            https://telelab.example.edu/lti/login" in printed
    assert "Public keyset (JWKS) URL:      https://telelab.example.edu/lti/jwks.json" in printed

    args[args.index("--key-set-url") + 1] = "ftp://moodle.example.edu/certs"
    assert main(args) == 2
    assert "key_set_url: The key-set (JWKS) URL must be a full address" in capsys.readouterr().err



def test_rotate_key_and_retire_key_change_what_the_jwks_serves(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    from middleware.lti.setup import _SENDER_KEY

    url = f"sqlite:///{tmp_path / 'keys.sqlite3'}"
    app = make_test_app(url, "", tmp_path)  # the served lab; each command below is a process of its own
    monkeypatch.setenv("TELELAB_DATABASE_URL", url)

    def served_kids() -> list[str]:
        with app.test_client() as client:
            return [key["kid"] for key in client.get("/lti/jwks.json").get_json()["keys"]]

    try:
        first = served_kids()
        assert len(first) == 1
        assert main(["lti", "rotate-key"]) == 0
        new = capsys.readouterr().out.split("new signing key ")[1].split(";")[0]
        assert served_kids() == [new, first[0]]  # the new key signs; the old one is still published
        assert main(["lti", "retire-key", new]) == 2  # the signing key is never retired
        assert "rotate to a new key first" in capsys.readouterr().err
        assert main(["lti", "retire-key", first[0]]) == 0
        assert served_kids() == [new]
    finally:
        _let_go(app)
        app.extensions[_SENDER_KEY].stop()
