"""The house rules of ARCHITECTURE.md section 1, checked on the source: the tiers meet only over gRPC."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def imported_modules(folder: str) -> dict[str, set[str]]:
    """For each Python file under folder, the top-level-qualified modules it imports."""
    found: dict[str, set[str]] = {}
    for path in (ROOT / folder).rglob("*.py"):
        names: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names.add(node.module)
        found[str(path.relative_to(ROOT))] = names
    return found


@pytest.mark.parametrize(
    ("folder", "forbidden"),
    [
        ("middleware", ("skill_server",)),
        ("skill_server", ("middleware",)),
        ("skill_server/sim", ("grpc", "protos", "grpc_health", "grpc_reflection")),
        ("skill_server/skills", ("grpc", "protos", "grpc_health", "grpc_reflection")),
        ("protos", ("middleware", "skill_server")),
    ],
)
def test_folder_does_not_import(folder: str, forbidden: tuple[str, ...]) -> None:
    offenders = {
        file: sorted(n for n in names if n.split(".")[0] in forbidden)
        for file, names in imported_modules(folder).items()
    }
    offenders = {file: names for file, names in offenders.items() if names}
    assert not offenders, f"{folder} must not import {forbidden}: {offenders}"


def test_every_top_level_folder_has_a_readme() -> None:
    for folder in ("client_ui", "middleware", "skill_server", "protos", "migrations", "tests"):
        assert (ROOT / folder / "README.md").is_file(), f"{folder}/README.md is missing"
