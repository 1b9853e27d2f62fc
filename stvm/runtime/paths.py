"""The one reader of variable paths typed by a user: `--set`, `--print`, `--until`, scenarios,
the trace, the debugger, the HMI and OPC UA all name a variable the way ST does.

    path    := name ( "." name | "[" index ("," index)* "]" | "^" )*
    name    := letter or "_", then letters, digits and "_"       (an ST identifier)
    index   := ["+" | "-"] an ST integer literal: 12, 1_000, 16#1F, 8#17, 2#1010

Spaces may stand around every token. The whole text must be a path: `Main..x`, `.Main.x`,
`Main.x.`, `Main.x; DROP`, `Main.a[1` are refused with the column of the problem, in ST terms.
Values are read by `stvm.semantics.literals.literal_value` (the ST grammar's own literals,
whole text consumed).

API (for the CLI, scenarios, the HMI and OPC UA):

* `parse_path(text) -> tuple[(kind, text), ...]`: ("name", "Q"), ("index", "1,2") (indices as
  decimal integers), ("deref", "^"); raises `PathSyntaxError` (a ValueError).
* `check_path(text) -> str`: the path as written, stripped, or PathSyntaxError.
* `MAX_PATH_CHARS`: the longest path read (a 5,000-character name is refused at once).
"""

from __future__ import annotations

import re

MAX_PATH_CHARS = 1024
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_INDEX = re.compile(r"([+-]?)\s*((?:2#|8#|16#)?[0-9A-Fa-f_]+)")
_BASES = {"2#": (2, "01"), "8#": (8, "01234567"), "16#": (16, "0123456789abcdefABCDEF")}


class PathSyntaxError(ValueError):
    """A variable path that is not written as ST names one."""


def _fail(text: str, pos: int, message: str) -> PathSyntaxError:
    shown = text if len(text) <= 60 else text[:57] + "..."
    return PathSyntaxError(f"{shown!r} is not a variable path: {message} (column {pos + 1})")


def _skip_spaces(text: str, pos: int) -> int:
    while pos < len(text) and text[pos] in " \t":
        pos += 1
    return pos


def _index(text: str, pos: int) -> tuple[int, int]:
    m = _INDEX.match(text, pos)
    if not m:
        raise _fail(text, pos, "an array index must be an integer, e.g. [2] or [1, 3]")
    sign, literal = m.group(1), m.group(2)
    base, digits_ok = 10, "0123456789"
    for prefix, (b, ok) in _BASES.items():
        if literal.startswith(prefix):
            base, digits_ok = b, ok
            literal = literal[len(prefix):]
            break
    if (not literal or literal.startswith("_") or literal.endswith("_") or "__" in literal
            or any(c not in digits_ok and c != "_" for c in literal) or len(literal) > 80):
        raise _fail(text, pos, f"{m.group(0).strip()!r} is not an ST integer")
    value = int(literal.replace("_", ""), base)
    return (-value if sign == "-" else value), m.end()


def parse_path(text: str) -> tuple[tuple[str, str], ...]:
    """The tokens of a variable path (see the module docstring); raises PathSyntaxError."""
    if not isinstance(text, str):
        raise PathSyntaxError(f"a variable path is text, not {type(text).__name__}")
    if len(text) > MAX_PATH_CHARS:
        raise PathSyntaxError(f"a variable path of {len(text)} characters is longer than the "
                              f"{MAX_PATH_CHARS} read")
    tokens: list[tuple[str, str]] = []
    pos = _skip_spaces(text, 0)
    if pos == len(text):
        raise PathSyntaxError("empty variable path: name a variable, e.g. Main.x or a global")
    m = _NAME.match(text, pos)
    if not m:
        raise _fail(text, pos, "a path starts with a name (a program or a global variable)")
    tokens.append(("name", m.group()))
    pos = _skip_spaces(text, m.end())
    while pos < len(text):
        ch = text[pos]
        if ch == ".":
            pos = _skip_spaces(text, pos + 1)
            m = _NAME.match(text, pos)
            if not m:
                raise _fail(text, pos, "a name must follow '.'")
            tokens.append(("name", m.group()))
            pos = m.end()
        elif ch == "[":
            indices = []
            pos = _skip_spaces(text, pos + 1)
            while True:
                value, pos = _index(text, pos)
                indices.append(str(value))
                pos = _skip_spaces(text, pos)
                if pos < len(text) and text[pos] == ",":
                    pos = _skip_spaces(text, pos + 1)
                    continue
                if pos < len(text) and text[pos] == "]":
                    pos += 1
                    break
                raise _fail(text, pos, "expected ',' or ']' in the array index")
            tokens.append(("index", ",".join(indices)))
        elif ch == "^":
            tokens.append(("deref", "^"))
            pos += 1
        else:
            raise _fail(text, pos, f"unexpected {ch!r} (a path continues with .name, [index] or ^)")
        pos = _skip_spaces(text, pos)
    return tuple(tokens)


def check_path(text: str) -> str:
    """`text` stripped, once it is known to be a well-formed path; raises PathSyntaxError."""
    parse_path(text)
    return text.strip()
