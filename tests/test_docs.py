"""The documentation stays true to the tree: the site builds with --strict (a broken link between its pages or to an
anchor fails it), every path a README or page names exists, and the settings table lists what the code reads."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SETTINGS_PAGE = ROOT / "docs" / "operator-guide" / "configuration.md"
NOT_IN_THE_TREE = {"site/", "site/index.html", "bench-results/"}  # what a build or a benchmark writes
WRITTEN_BY_THE_TESTS = "test-artifacts/"  # exists once the test that writes it has run, maybe in another process
SKIPPED_FOLDERS = {".git", ".venv", "node_modules", "site", "telelab.egg-info", "instance", "test-artifacts"}
SETTING = re.compile(r"\bTELELAB_[A-Z0-9_]*[A-Z0-9]\b")


def build_site(config: Path, site_dir: Path) -> subprocess.CompletedProcess[str]:
    """`mkdocs build --strict` of config into site_dir, from the repository's root (the snippets' base)."""
    environment = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", str(config),
                           "--site-dir", str(site_dir)], cwd=ROOT, env=environment, capture_output=True,
                          text=True, timeout=120)


def test_the_site_builds_with_strict_link_checks(tmp_path: Path) -> None:
    built = build_site(ROOT / "mkdocs.yml", tmp_path / "site")

    assert built.returncode == 0, built.stderr
    assert (tmp_path / "site" / "operator-guide" / "configuration.html").is_file()
    where = (tmp_path / "site" / "develop" / "where-to-change.html").read_text()
    assert "KEY_DIRECTIONS" in where and "PANEL_MODULES" in where  # the README's table, included


def test_a_broken_link_between_pages_fails_the_build(tmp_path: Path) -> None:
    docs = tmp_path / "docs"
    shutil.copytree(ROOT / "docs", docs)
    index = docs / "index.md"
    index.write_text(index.read_text() + "\nSee [the old guide](operator-guide/gone.md).\n")
    config = tmp_path / "mkdocs.yml"
    config.write_text(f"INHERIT: {ROOT / 'mkdocs.yml'}\ndocs_dir: {docs}\n")

    built = build_site(config, tmp_path / "site")

    assert built.returncode != 0
    assert "operator-guide/gone.md" in built.stderr


def documents() -> list[Path]:
    """Every README of the tree and every page of the site."""
    readmes = [p for p in ROOT.rglob("README.md") if not SKIPPED_FOLDERS.intersection(p.relative_to(ROOT).parts)]
    return sorted(readmes) + sorted((ROOT / "docs").rglob("*.md"))


def named_paths(text: str) -> list[str]:
    """The paths in code spans: `a/b.py`, `static/lib/` (bare file names are read within their folder's context)."""
    spans = (span.strip() for span in re.findall(r"`([^`\n]+)`", text))
    return [s for s in spans if "/" in s and re.fullmatch(r"[\w.\-/]+", s) and not s.startswith(("/", "../shared"))
            and (s.endswith("/") or re.search(r"\.[a-z]+$", s))]


def exists_from(document: Path, path: str) -> bool:
    """A path is named from its document's folder, one above it, or the tier folder it is about."""
    bases = [document.parent, *document.parent.parents, ROOT / "client_ui", ROOT / "client_ui" / "static"]
    return any((base / path).exists() for base in bases if base == ROOT or ROOT in base.parents)


@pytest.mark.parametrize("document", documents(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_path_a_document_names_exists(document: Path) -> None:
    missing = [path for path in named_paths(document.read_text())
               if path not in NOT_IN_THE_TREE and not path.startswith(WRITTEN_BY_THE_TESTS)
               and not exists_from(document, path)]

    assert not missing, f"{document.relative_to(ROOT)} names paths that are not in the tree: {missing}"


def settings_read_by(folders: list[str]) -> set[str]:
    """The TELELAB_ settings named in the Python code of folders."""
    return {name for folder in folders for source in (ROOT / folder).rglob("*.py")
            for name in SETTING.findall(source.read_text())}


def test_the_settings_page_lists_every_setting_the_code_reads() -> None:
    documented = set(SETTING.findall(SETTINGS_PAGE.read_text()))
    read = settings_read_by(["middleware", "skill_server", "benchmarks"]) | settings_read_by(["tests"]) & {
        "TELELAB_TEST_POSTGRES_URL", "TELELAB_SKIP_POSTGRES"}

    assert read - documented == set(), "settings the code reads that docs/operator-guide/configuration.md omits"
    assert documented - read - settings_read_by(["tests"]) == set(), "settings documented that nothing reads"


def where_to_change_rows() -> list[tuple[str, str]]:
    """The rows of the top-level README's *Where to change what* table: (what to change, where)."""
    section = (ROOT / "README.md").read_text().split("## Where to change what", 1)[1]
    rows = [[cell.strip() for cell in line.strip().strip("|").split("|")] for line in section.splitlines()
            if line.startswith("|") and not line.startswith("|---")]
    return [(what, where) for what, where in rows[1:]]


def test_the_readme_answers_where_the_up_arrow_and_a_new_sensor_panel_are_changed() -> None:
    rows = dict(where_to_change_rows())

    assert any("up arrow" in what for what in rows) and any("new sensor" in what for what in rows)


@pytest.mark.parametrize("what, where", where_to_change_rows(), ids=lambda cell: cell[:40])
def test_every_name_the_where_to_change_table_gives_is_in_a_file_it_names(what: str, where: str) -> None:
    spans = re.findall(r"`([^`]+)`", where)
    files = [ROOT / s for s in spans if "/" in s and (ROOT / s).is_file()]
    names = [s for s in spans if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", s) and not s.startswith("TELELAB_")]

    missing = [name for name in names if not any(name in f.read_text() for f in files)]
    assert not missing, f"'{what}': {missing} are in none of {[str(f.relative_to(ROOT)) for f in files]}"


README_LINES = 200  # a README states what a reader needs and the rules; guides and figures live elsewhere
FRONT_PAGE_LINES = 100


@pytest.mark.parametrize("readme", [d for d in documents() if d.name == "README.md"],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_a_readme_stays_short(readme: Path) -> None:
    limit = FRONT_PAGE_LINES if readme.parent == ROOT else README_LINES
    lines = len(readme.read_text().splitlines())

    assert lines <= limit, (f"{readme.relative_to(ROOT)} has {lines} lines (at most {limit}): move guides to docs/, "
                            "figures to benchmarks/results/, an area's details to its own README")
