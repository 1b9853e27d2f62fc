"""Lark's parser tables for st.lark, generated as text and shipped with stvm (first-run time).

Building the LALR tables from the grammar takes about a second, which every user would pay on a
first run (and again for every new cache folder: CI, a fresh `STVM_CACHE_DIR`). The tables are
stored beside the grammar as JSON (`st_tables.json`): Lark's own serialised form (what its
`save()` pickles and its standalone generator prints as a Python literal), under a key made of
the grammar text, the Lark options, Lark's version and Python's major.minor. A key that does not
match (an edited grammar, another Lark) means the file is not used: the tables are built, and
kept as the same JSON text in stvm's signed cache (`stvm.cache`), never as a pickle.

Why JSON and not a generated Python module as Lark's standalone generator writes: the literal is
~490 KB of nested tuples and dicts, which CPython takes ~1.5 s to compile, paid by every process
where no `.pyc` can be written (`PYTHONDONTWRITEBYTECODE`, read-only installs); `json.loads`
reads it in ~30 ms. Like a module it is text: reviewed as a diff, and nothing in it runs.

JSON has no tuples and only string keys, so the file tags them: `{"(": [...]}` is a tuple and
`{"{": [[key, value], ...]}` a dict with keys that are not all strings (the parse table's state
numbers).

Reproducible: Lark numbers tokens and states in an order that follows hashing (of strings, and of
objects by identity), so the generator renumbers the parse table canonically (tokens by name,
states breadth-first from the start states) and runs under `PYTHONHASHSEED=0`: the same grammar,
options and Lark give the same bytes.
Regenerate after changing the grammar or upgrading Lark (tests/syntax/test_tables.py fails when
the file is stale or not what the generator writes):

    python -m stvm.syntax.gen_tables [--check]
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import lark
from lark import Lark

FILE = Path(__file__).with_name("st_tables.json")
FORMAT = "stvm-lark-tables-json-1"

# what Lark's serialised form leaves out and its loader takes again (functions of the caller)
_CALLER_OPTIONS = ("lexer_callbacks",)


def key(grammar: str, options: dict) -> str:
    """What the tables are built from: grammar, options (without the caller's callbacks), Lark, Python."""
    digest = hashlib.sha256(b"stvm-lark-tables\0")
    for part in (grammar, repr(sorted((k, v) for k, v in options.items() if k not in _CALLER_OPTIONS)),
                 lark.__version__, repr(sys.version_info[:2])):
        digest.update(part.encode("utf-8") + b"\0")
    return digest.hexdigest()


# ---- the JSON form ----------------------------------------------------------------------------

def _encode(value):
    if isinstance(value, tuple):
        return {"(": [_encode(v) for v in value]}
    if isinstance(value, list):
        return [_encode(v) for v in value]
    if isinstance(value, dict):
        if all(isinstance(k, str) for k in value):
            return {k: _encode(v) for k, v in value.items()}
        return {"{": [[_encode(k), _encode(v)] for k, v in value.items()]}
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"Lark's serialised tables hold a {type(value).__name__}, which the JSON form cannot keep")


def _decode_object(obj: dict):
    if len(obj) == 1:
        if "(" in obj:
            return tuple(obj["("])
        if "{" in obj:
            return {_hashable(k): v for k, v in obj["{"]}
    return obj


def _hashable(value):
    return tuple(_hashable(v) for v in value) if isinstance(value, list) else value


def to_text(grammar: str, options: dict, serialised: dict) -> str:
    """The file's text for Lark's serialised tables (`{'data': …, 'memo': …}`)."""
    document = {"format": FORMAT, "key": key(grammar, options), "lark": lark.__version__,
                "tables": _encode(serialised)}
    # one item a line: a grammar change shows as a readable diff
    return json.dumps(document, indent=0, ensure_ascii=True) + "\n"


def from_text(text: str, grammar: str, options: dict) -> Lark | None:
    """The Lark parser held by `text` when it was built from exactly this grammar and these
    options, else None (stale, damaged, or another format)."""
    try:
        document = json.loads(text, object_hook=_decode_object)
    except ValueError:
        return None
    if not isinstance(document, dict) or document.get("format") != FORMAT or document.get("key") != key(grammar, options):
        return None
    try:
        return Lark.__new__(Lark)._load(document["tables"], **{k: v for k, v in options.items() if k in _CALLER_OPTIONS})
    except Exception:   # noqa: BLE001 - a Lark whose classes changed under the same version: build instead
        return None


def serialise(parser: Lark) -> dict:
    """What `Lark.save()` would pickle, as plain data, its parse table in canonical order."""
    data, memo = parser.memo_serialize([lark.lexer.TerminalDef, lark.grammar.Rule])
    data["options"] = {n: v for n, v in data["options"].items() if n not in _CALLER_OPTIONS}
    data["parser"]["parser"] = canonical_parse_table(data["parser"]["parser"])
    return {"data": data, "memo": memo}


_SHIFT = 0   # the action code of a shift in Lark's serialised parse table (1 is a reduce)


def canonical_parse_table(table: dict) -> dict:
    """The same LALR automaton numbered independently of how Lark happened to build it.

    Lark numbers tokens and states in the order it meets them while iterating sets of objects
    hashed by identity, so two builds of one grammar differ even under a fixed PYTHONHASHSEED.
    Here tokens are numbered by name, and states in breadth-first order from the start states
    (taken by name), following shifts in token-name order."""
    names = table["tokens"]
    token_index = {name: i for i, name in enumerate(sorted(set(names.values())))}
    states = table["states"]
    order: dict[int, int] = {}
    queue = [table["start_states"][start] for start in sorted(table["start_states"])]
    queue += [table["end_states"][start] for start in sorted(table["end_states"])]
    for state in queue:   # the list grows while it is walked: breadth first
        if state in order:
            continue
        order[state] = len(order)
        actions = states[state]
        for token in sorted(actions, key=names.__getitem__):
            action, arg = actions[token]
            if action == _SHIFT and arg not in order:
                queue.append(arg)
    if len(order) != len(states):
        raise ValueError("the parse table has states no start state reaches")

    def action(pair):
        code, arg = pair
        return (code, order[arg]) if code == _SHIFT else (code, arg)

    return {
        "tokens": {i: name for name, i in token_index.items()},
        "states": {order[state]: {token_index[names[token]]: action(states[state][token])
                                  for token in sorted(states[state], key=names.__getitem__)}
                   for state in sorted(states, key=order.__getitem__)},
        "start_states": {start: order[s] for start, s in sorted(table["start_states"].items())},
        "end_states": {start: order[s] for start, s in sorted(table["end_states"].items())},
    }


# ---- the shipped file -------------------------------------------------------------------------

def load(grammar: str, options: dict) -> Lark | None:
    """The Lark parser from the shipped tables when they were built from exactly this grammar and
    these options, else None."""
    try:
        text = FILE.read_text(encoding="ascii")
    except (OSError, UnicodeDecodeError):
        return None
    return from_text(text, grammar, options)


def generate(grammar: str, options: dict) -> str:
    """The shipped file's text for this grammar, built with Lark under `PYTHONHASHSEED=0` (in a
    child process when this one hashes strings otherwise), so the result is reproducible."""
    if os.environ.get("PYTHONHASHSEED") == "0":
        return to_text(grammar, options, serialise(Lark(grammar, **options)))
    done = subprocess.run([sys.executable, "-m", "stvm.syntax.gen_tables", "--print"],
                          env={**os.environ, "PYTHONHASHSEED": "0"}, capture_output=True, text=True,
                          check=True, cwd=Path(__file__).resolve().parents[2])
    return done.stdout
