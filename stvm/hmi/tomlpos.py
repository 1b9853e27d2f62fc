"""Where a key of a TOML file is: `(line, column)` for error messages (`tomllib` keeps none).

A light line scanner, good for the files a person writes (tables, arrays of tables, `key = value`
lines, multi-line strings and arrays); it is never used to read values. A location is asked for
by the path the parsed data has, e.g. `("area", 0, "widget", 2, "var")`: the second widget of the
first area's `var` key. A path the scanner did not see (a key inside an inline table) answers
with its nearest known parent, so every error still points at the right line.
"""

from __future__ import annotations

import re

_HEADER = re.compile(r"\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_KEY = re.compile(r"""\s*((?:[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*"|'[^']*')(?:\s*\.\s*(?:[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*"|'[^']*'))*)\s*=""")
_KEY_PART = re.compile(r"""\s*([A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*"|'[^']*')\s*\.?""")


def _split_key(text: str) -> list[str]:
    parts = []
    pos = 0
    while pos < len(text):
        m = _KEY_PART.match(text, pos)
        if not m or m.end() == pos:
            break
        raw = m.group(1)
        parts.append(raw[1:-1] if raw[:1] in "\"'" else raw)
        pos = m.end()
    return parts


class TomlLocator:
    def __init__(self, text: str) -> None:
        self._where: dict[tuple, tuple[int, int]] = {}
        self._arrays: dict[tuple, int] = {}
        self._scan(text)

    def locate(self, path: tuple) -> tuple[int, int]:
        """(line, column), 1-based, of the key at `path` or of its nearest known parent; (1, 1)
        if nothing is known."""
        path = tuple(path)
        while path:
            if path in self._where:
                return self._where[path]
            path = path[:-1]
        return (1, 1)

    # ---- scanning
    def _table(self, keys: list[str], is_array: bool) -> tuple:
        path: list = []
        for i, key in enumerate(keys):
            path.append(key)
            prefix = tuple(path)
            last = i == len(keys) - 1
            if prefix in self._arrays:
                if last and is_array:
                    self._arrays[prefix] += 1
                path.append(self._arrays[prefix])
            elif last and is_array:
                self._arrays[prefix] = 0
                path.append(0)
        return tuple(path)

    def _scan(self, text: str) -> None:
        table: tuple = ()
        skip_until: str | None = None   # the closing delimiter of a multi-line value
        depth = 0                       # open brackets of a multi-line array
        for number, line in enumerate(text.splitlines(), start=1):
            if skip_until is not None:
                if skip_until in line:
                    skip_until = None
                continue
            if depth > 0:
                depth += _bracket_balance(line)
                continue
            stripped = line.strip()
            if not stripped or stripped.startswith("#"):
                continue
            header = _HEADER.match(line) if stripped.startswith("[") else None
            if header:
                table = self._table(_split_key(header.group(2)), header.group(1) == "[[")
                self._where.setdefault(table, (number, line.index("[") + 1))
                continue
            key = _KEY.match(line)
            if not key:
                continue
            parts = _split_key(key.group(1))
            column = len(line) - len(line.lstrip()) + 1
            self._where[table + tuple(parts)] = (number, column)
            value = line[key.end():]
            for quote in ('"""', "'''"):
                if value.strip().startswith(quote) and value.count(quote) == 1:
                    skip_until = quote
            if skip_until is None:
                depth = max(0, _bracket_balance(value))


def _bracket_balance(text: str) -> int:
    """Open minus closed brackets outside strings and comments (enough for arrays of values)."""
    balance = 0
    quote = None
    for ch in text:
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            break
        elif ch in "[{":
            balance += 1
        elif ch in "]}":
            balance -= 1
    return balance
