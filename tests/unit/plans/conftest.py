"""The real catalogue's skill schemas, as the middleware receives them over ListSkills, for the plan tests."""

from __future__ import annotations

import pytest

from middleware.teaching.command_form import SkillSchemas
from tests.unit.plans.catalogue import catalogue_schemas


@pytest.fixture(scope="session")
def skills() -> SkillSchemas:
    """Every skill of the default registry, through the proto form and middleware.robots.messages, so a change
    to a skill's schema changes what these tests accept."""
    return catalogue_schemas()
