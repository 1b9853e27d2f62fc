"""LSP positions count UTF-16 code units (the protocol's default encoding): on a line holding
characters beyond U+FFFF (two units each) and other non-ASCII ones, in a comment and in a
WSTRING literal, hover, definition, references, rename and diagnostics point at the right text.
"""

from __future__ import annotations

import pytest
from lsprotocol import types as lsp

from lsp_helpers import FIXTURES, doc, open_file
from stvm.lsp import positions as pos

MAIN = FIXTURES / "unicode" / "Main.st"
BROKEN = FIXTURES / "unicode_error" / "Main.st"
pytestmark = pytest.mark.asyncio(loop_scope="module")


def utf16(text: str) -> int:
    return len(text.encode("utf-16-le")) // 2


def where(path, needle: str, nth: int = 0) -> lsp.Position:
    """The position of the nth `needle` in `path`, its character in UTF-16 code units."""
    text = path.read_text(encoding="utf-8")
    at = -1
    for _ in range(nth + 1):
        at = text.index(needle, at + 1)
    line_start = text.rfind("\n", 0, at) + 1
    return lsp.Position(text.count("\n", 0, at), utf16(text[line_start:at]))


def text_of(path, rng: lsp.Range) -> str:
    """The text a range covers, its characters read as UTF-16 code units."""
    line = path.read_text(encoding="utf-8").split("\n")[rng.start.line].encode("utf-16-le")
    assert rng.start.line == rng.end.line
    return line[2 * rng.start.character:2 * rng.end.character].decode("utf-16-le")


def test_the_fixture_has_what_the_test_is_about():
    line = MAIN.read_text(encoding="utf-8").split("\n")[4]
    assert any(ord(c) > 0xFFFF for c in line) and any(0x7F < ord(c) <= 0xFFFF for c in line)
    assert utf16(line) > len(line)


async def test_hover_range_after_astral_characters_in_a_comment_and_a_wstring(client):
    await open_file(client, MAIN)
    for nth in (1, 3):      # after the comment; after the WSTRING literal
        at = where(MAIN, "counter", nth)
        hover = await client.text_document_hover_async(lsp.HoverParams(doc(MAIN), at))
        assert hover is not None and "INT" in hover.contents.value
        assert hover.range.start == at and text_of(MAIN, hover.range) == "counter"


async def test_definition_and_references_in_utf16(client):
    await open_file(client, MAIN)
    found = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), where(MAIN, "counter", 4)))
    assert [loc.range.start for loc in found] == [where(MAIN, "counter", 0)]
    assert text_of(MAIN, found[0].range) == "counter"
    refs = await client.text_document_references_async(lsp.ReferenceParams(
        text_document=doc(MAIN), position=where(MAIN, "counter", 2),
        context=lsp.ReferenceContext(include_declaration=True)))
    assert sorted((r.range.start.line, r.range.start.character) for r in refs) == \
        sorted((p.line, p.character) for p in (where(MAIN, "counter", i) for i in range(5)))
    assert {text_of(MAIN, r.range) for r in refs} == {"counter"}


async def test_a_position_inside_the_surrogate_pair_before_a_name_finds_nothing_wrong(client):
    await open_file(client, MAIN)
    at = where(MAIN, "ws :=", 0)      # `ws` after the WSTRING literal "𝄞x" of line 5
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(MAIN), lsp.Position(at.line, at.character + 1)))
    assert hover is not None and "WSTRING" in hover.contents.value and text_of(MAIN, hover.range) == "ws"


async def test_rename_edits_in_utf16(client):
    await open_file(client, MAIN)
    edit = await client.text_document_rename_async(lsp.RenameParams(
        text_document=doc(MAIN), position=where(MAIN, "counter", 3), new_name="n"))
    spots = next(iter(edit.changes.values()))
    assert len(spots) == 5 and {text_of(MAIN, e.range) for e in spots} == {"counter"}


async def test_diagnostic_range_in_utf16(client):
    diags = await open_file(client, BROKEN)
    [d] = [d for d in diags if d.code == "E031"]
    assert d.range.start == where(BROKEN, "missing") and text_of(BROKEN, d.range) == "missing"
    assert d.code_description is not None and d.code_description.href.endswith("error_codes.md#e031")

def test_conversion_both_ways_and_other_encodings():
    text = "a\n(* 😀 é *) x\n"
    assert pos.to_client(text, 1, 11, pos.UTF16) == 12
    assert pos.from_client(text, 1, 12, pos.UTF16) == 11
    assert pos.from_client(text, 1, 4, pos.UTF16) == 3      # inside the pair: the character's start
    assert pos.to_client(text, 1, 11, pos.UTF8) == 15        # 😀 is 4 bytes, é 2
    assert pos.from_client(text, 1, 15, pos.UTF8) == 11
    assert pos.to_client(text, 1, 11, pos.UTF32) == 11
    assert pos.to_client(text, 0, 1, pos.UTF16) == 1 and pos.to_client("plain\n", 0, 3, pos.UTF16) == 3
    data = [1, 10, 1, 0, 0]      # one token: `x`, line 1, column 10, length 1
    assert pos.semantic_tokens_out(data, text, pos.UTF16) == [1, 11, 1, 0, 0]
