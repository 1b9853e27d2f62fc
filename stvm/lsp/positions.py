"""Columns as the client counts them (LSP `positionEncoding`, UTF-16 code units by default).

stvm's spans and the position index count columns in code points (Python `str` indices). LSP
counts `Position.character` in the encoding negotiated at `initialize`: UTF-16 code units
unless the client offers `utf-32` or `utf-8` first (pygls chooses; `workspace.position_encoding`
says which). In UTF-16 a character beyond U+FFFF (an emoji in a comment, a CJK extension
character in a WSTRING literal) is two units, so every column after one on its line differs.
The server converts at its boundary: a request's position from the client's units to code
points, every Range and Position it answers back to the client's units.

A line without such characters is the same in UTF-16 and code points, so the common case (a
file of ASCII and BMP text) costs one regex search per file text, cached.
"""

from __future__ import annotations

import functools
import re

from lsprotocol import types as lsp

UTF8, UTF16, UTF32 = "utf-8", "utf-16", "utf-32"
_ASTRAL = re.compile("[\U00010000-\U0010ffff]")


@functools.lru_cache(maxsize=64)
def _lines_needing_care(text: str, encoding: str) -> dict[int, str] | None:
    """{line number: its text} of the lines whose columns differ between code points and
    `encoding`; None when no line does (strings hash once, so the cache key is cheap)."""
    if encoding == UTF32:
        return None
    pattern = _ASTRAL if encoding == UTF16 else re.compile("[^\x00-\x7f]")
    if pattern.search(text) is None:
        return None
    return {i: line for i, line in enumerate(text.split("\n")) if pattern.search(line)}


def _units(text: str, encoding: str) -> int:
    if encoding == UTF16:
        return len(text) + len(_ASTRAL.findall(text))
    return len(text.encode("utf-8", "surrogatepass"))


def to_client(text: str | None, line: int, col: int, encoding: str) -> int:
    """The column `col` (code points, 0-based) of `line` in `text`, in the client's units."""
    care = _lines_needing_care(text, encoding) if text else None
    if not care or line not in care:
        return col
    return _units(care[line][:col], encoding)


def from_client(text: str | None, line: int, character: int, encoding: str) -> int:
    """The code-point column of the client's `character` (its units) on `line` of `text`; a
    position inside a character (half a surrogate pair) is taken as that character's start."""
    care = _lines_needing_care(text, encoding) if text else None
    if not care or line not in care:
        return character
    source, units = care[line], 0
    for i, ch in enumerate(source):
        step = _units(ch, encoding)
        if units + step > character:
            return i
        units += step
    return len(source) + (character - units)   # past the end: as far past it as the client said


def convert_out(value, text_of, uri: str | None, encoding: str):
    """`value` (an lsprotocol answer, a list of them, or None) with every Range and Position
    in the client's units, in place. `text_of(uri)` is the text a position of `uri` refers to;
    positions belong to `uri` (the request's document) unless a Location, LocationLink or
    WorkspaceEdit names another."""
    if encoding == UTF32 or value is None:
        return value
    _walk(value, text_of, uri, encoding, set())
    return value


def _walk(value, text_of, uri, encoding, seen) -> None:
    if isinstance(value, (str, int, float, bool)) or value is None or id(value) in seen:
        return
    seen.add(id(value))
    if isinstance(value, (list, tuple)):
        for item in value:
            _walk(item, text_of, uri, encoding, seen)
        return
    if isinstance(value, dict):
        for key, item in value.items():
            # WorkspaceEdit.changes: {uri: [TextEdit]}
            _walk(item, text_of, key if isinstance(key, str) and ":" in key else uri, encoding, seen)
        return
    if isinstance(value, lsp.Position):
        value.character = to_client(text_of(uri), value.line, value.character, encoding)
        return
    if isinstance(value, lsp.CompletionItem):
        # hundreds per answer: only their edits hold positions
        _walk(value.text_edit, text_of, uri, encoding, seen)
        _walk(value.additional_text_edits, text_of, uri, encoding, seen)
        return
    if isinstance(value, (lsp.MarkupContent, lsp.SignatureHelp)):
        return
    if isinstance(value, lsp.Location):
        uri = value.uri
    elif isinstance(value, lsp.LocationLink):
        uri = value.target_uri
    elif isinstance(value, lsp.TextDocumentEdit):
        uri = value.text_document.uri
    fields = getattr(type(value), "__attrs_attrs__", None)
    if fields is None:
        return
    for field in fields:
        _walk(getattr(value, field.name), text_of, uri, encoding, seen)


def semantic_tokens_out(data: list[int], text: str | None, encoding: str) -> list[int]:
    """Semantic tokens (relative line, relative start, length, type, modifiers) with their
    start and length in the client's units."""
    if encoding == UTF32 or not text or _lines_needing_care(text, encoding) is None:
        return data
    out, line, col, prev_line, prev_col = [], 0, 0, 0, 0
    for i in range(0, len(data), 5):
        dl, dc, length, kind, mods = data[i:i + 5]
        line += dl
        col = col + dc if dl == 0 else dc
        start = to_client(text, line, col, encoding)
        end = to_client(text, line, col + length, encoding)
        out += [line - prev_line, start - prev_col if line == prev_line else start, end - start, kind, mods]
        prev_line, prev_col = line, start
    return out
