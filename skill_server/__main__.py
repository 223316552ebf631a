"""`python -m skill_server --port 50051`: runs one robot's skill server."""

from __future__ import annotations

import sys

from skill_server.server import main

if __name__ == "__main__":
    sys.exit(main())
