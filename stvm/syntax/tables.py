"""Lark's parser tables for st.lark, built once and shipped with stvm (first-run time).

Building the LALR tables from the grammar takes about a second, which every user paid on their
first run (and again for every new cache folder: CI, a fresh `STVM_CACHE_DIR`). The tables are
stored beside the grammar (`st_tables.pickle`, Lark's own `save()` format) under a key: the
grammar text, the Lark options, Lark's version and Python's major.minor. A key that does not
match (an edited grammar, another Lark) means the file is not used: Lark builds the tables (and
keeps them in the user's private cache folder, parser.py) as before, so a stale file costs time,
never correctness.

Trust: the file is part of the installed package, like its `.py` files (whoever can replace it
can replace those); it is only read from this folder, never from a cache folder.

Rebuild it after changing the grammar or upgrading Lark (tests/syntax/test_tables.py says when
it is stale); the stdlib's prebuilt step rebuilds it first (`parser.build_shipped_tables`):

    python -m stvm.stdlib.prebuilt
"""

from __future__ import annotations

import hashlib
import io
import sys
from pathlib import Path

import lark
from lark import Lark

from stvm.folders import read_keyed, write_keyed

FILE = Path(__file__).with_name("st_tables.pickle")

# what Lark's save() leaves out and load() takes again (functions and objects of the caller)
_CALLER_OPTIONS = ("lexer_callbacks",)


def key(grammar: str, options: dict) -> str:
    """What the tables are built from: grammar, options (without the caller's callbacks), Lark, Python."""
    digest = hashlib.sha256(b"stvm-lark-tables\0")
    for part in (grammar, repr(sorted((k, v) for k, v in options.items() if k not in _CALLER_OPTIONS)),
                 lark.__version__, repr(sys.version_info[:2])):
        digest.update(part.encode("utf-8") + b"\0")
    return digest.hexdigest()


def load(grammar: str, options: dict) -> Lark | None:
    """The Lark parser from the shipped tables when they were built from exactly this grammar and
    these options, else None."""
    body = read_keyed(FILE, key(grammar, options))
    return None if body is None else from_bytes(body, options)


def from_bytes(body: bytes, options: dict) -> Lark | None:
    """A Lark parser from tables written by `to_bytes` (None if they do not load). Only for
    trusted bytes: the shipped file, or a signed cache entry (Lark's format is a pickle)."""
    try:
        # what Lark's own `cache=` does with its file (`Lark.load` takes no options; the lexer
        # callbacks are functions, left out of the file and given again here)
        return Lark.__new__(Lark)._load(io.BytesIO(body), **{k: v for k, v in options.items() if k in _CALLER_OPTIONS})
    except Exception:   # damaged, or a Lark whose classes changed under the same version: build instead
        return None


def to_bytes(parser: Lark) -> bytes:
    out = io.BytesIO()
    parser.save(out, exclude_options=_CALLER_OPTIONS)
    return out.getvalue()


def build(grammar: str, options: dict, file: Path = FILE) -> Path:
    """Build the tables with Lark and write the file, unless it already holds tables that load for
    exactly this key: Lark numbers its states differently on every build (string hashing), so a
    rebuild of unchanged tables would rewrite the file with a new binary for nothing."""
    if file == FILE and load(grammar, options) is not None:
        return file
    parser = Lark(grammar, **options)
    write_keyed(file, key(grammar, options), to_bytes(parser))
    return file
