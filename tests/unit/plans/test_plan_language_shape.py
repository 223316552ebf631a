"""The language stays pure: no request state, no gRPC, no database, no skill server; protos only in proto_form.
And the parameter check it shares with command_form still serves command_form's own callers."""

from __future__ import annotations

from pathlib import Path

import pytest

from middleware.teaching.command_form import CommandInvalid, check_parameter, parse_command
from tests.test_architecture import imports_in

PLANS = Path(__file__).resolve().parents[3] / "middleware" / "plans"
LANGUAGE_MODULES = ("__init__", "language", "steps", "checks", "tokens", "text_form", "text_commands", "text_writer",
                    "json_form", "summary", "aliases", "proto_form")
FORBIDDEN = ("flask", "flask_login", "grpc", "sqlalchemy", "skill_server", "middleware.db", "middleware.models",
             "middleware.robots", "middleware.access")


@pytest.mark.parametrize("module", LANGUAGE_MODULES)
def test_the_language_imports_nothing_that_runs_or_stores(module: str) -> None:
    imported = imports_in(PLANS / f"{module}.py")
    assert not {name for name in imported for bad in FORBIDDEN if name == bad or name.startswith(bad + ".")}
    if module != "proto_form":
        assert not {name for name in imported if name.startswith("protos")}
    assert not {name for name in imported if name in ("re", "builtins", "importlib", "pickle")}, \
        "the text is read by hand: no regular expressions, no dynamic code"


def test_the_shared_parameter_check_refuses_an_int_too_large_for_a_float() -> None:
    with pytest.raises(CommandInvalid) as refused:
        check_parameter("goal_x_m", 10**400, {"type": "double", "minimum": -5, "maximum": 5})
    assert refused.value.field == "parameters.goal_x_m"
    with pytest.raises(CommandInvalid):
        parse_command({"drive": {"linear_mps": 10**400}}, None)
    assert parse_command({"skill": "go_to_goal", "parameters": {"goal_x_m": 2}},
                         {"go_to_goal": [{"name": "goal_x_m", "type": "double", "minimum": -5, "maximum": 5}]}
                         ).parameters == (("goal_x_m", 2.0),)
