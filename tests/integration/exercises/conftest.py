"""The exercises' API tests use the plans tests' lab (student1 and student2 in ROB1 taught by tutor1, tutor2 teaching
ROB2 with student3, admin1), wired to the session's real skill server."""

from __future__ import annotations

from tests.integration.plans.conftest import plans_lab  # noqa: F401 - the fixture, shared
