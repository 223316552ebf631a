"""The suite makes a Flask app per test (about 1 500 of them), and werkzeug compiles two URL-builder functions per
rule of each app's URL map (Python source, through `ast` and `compile`): 90 % of `create_app`'s time, 0.8 s of a
quiet core per app. The builder's code depends only on the rule's text, its parts, its defaults and whether it
appends unknown arguments (the rule itself is passed in as an argument), so one process compiles each builder
once and every later app reuses it. The functions are werkzeug's own: nothing the tests check changes."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from werkzeug.routing.rules import Rule

_builders: dict[tuple[Any, ...], Callable[..., tuple[str, str]]] = {}
_compile_builder = Rule._compile_builder


def _shared_compile_builder(self: Rule, append_unknown: bool = True) -> Callable[..., tuple[str, str]]:
    defaults = self.defaults or {}
    key = (self.rule, tuple(self._trace), append_unknown, tuple(sorted((name, repr(value), type(self._converters.get(
        name)).__qualname__) for name, value in defaults.items())))
    builder = _builders.get(key)
    if builder is None:
        builder = _builders[key] = _compile_builder(self, append_unknown)
    return builder


def install() -> None:
    """Shares the compiled builders within this process from now on."""
    Rule._compile_builder = _shared_compile_builder  # type: ignore[method-assign]
