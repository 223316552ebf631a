"""`telelab lti register` registers an LMS and prints what its administrator pastes; a wrong field is named."""

from __future__ import annotations

from pathlib import Path

import pytest

from middleware.cli import main
from tests.conftest import migrate_to_head


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
