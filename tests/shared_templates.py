"""Each of the suite's apps (about 1 500) compiled every template it rendered anew: Jinja's lexer, parser, code
generator and `compile` took some 17 CPU-s of a run's pytest processes. One process compiles a template once and
every later app loads its code: Jinja's own bytecode cache, keyed by the template's name and a checksum of its
source, so a changed template is compiled again. What a template renders does not change."""

from __future__ import annotations

from flask import Flask
from jinja2 import BytecodeCache
from jinja2.bccache import Bucket


class ProcessBytecodeCache(BytecodeCache):
    """Compiled templates kept in this process's memory."""

    def __init__(self) -> None:
        self._code: dict[str, bytes] = {}

    def load_bytecode(self, bucket: Bucket) -> None:
        code = self._code.get(bucket.key)
        if code is not None:
            bucket.bytecode_from_string(code)

    def dump_bytecode(self, bucket: Bucket) -> None:
        self._code[bucket.key] = bucket.bytecode_to_string()


def install() -> None:
    """Every Flask app this process makes from now on shares one cache of compiled templates."""
    Flask.jinja_options = {**Flask.jinja_options, "bytecode_cache": ProcessBytecodeCache()}
