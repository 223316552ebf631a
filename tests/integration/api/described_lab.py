"""The seeded demo lab of tests/hardening served by a process of its own, for the Schemathesis run: the server's
work does not share an interpreter (and its lock) with the cases' generation, so the two use both cores.

Run as `python -m tests.integration.api.described_lab <folder>`: it prints one JSON line {"url", "passwords"}
once serving, and serves until its standard input closes.
"""

from __future__ import annotations

import json
import sys
import threading
from pathlib import Path

from middleware.serve import make_threaded_server
from tests.hardening.conftest import seeded_lab, stop_lab


def main(folder: str) -> None:
    """Seeds and serves the lab until stdin closes."""
    tmp_path = Path(folder)
    app = seeded_lab(f"sqlite:///{tmp_path / 'lab.sqlite3'}", tmp_path)
    server = make_threaded_server(app, "127.0.0.1", 0)
    threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True).start()
    print(json.dumps({"url": f"http://127.0.0.1:{server.server_port}", "passwords": app.config["TEST_PASSWORDS"]}),
          flush=True)
    sys.stdin.read()
    server.shutdown()
    server.server_close()
    stop_lab(app)


if __name__ == "__main__":
    main(sys.argv[1])
