"""Helpers of the LSP tests: the fixture folders, positions named by the text at them."""

from __future__ import annotations

from pathlib import Path

from lsprotocol import types as lsp
from pytest_lsp import LanguageClient

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = Path(__file__).resolve().parent / "fixtures"


def position(path: Path, needle: str, nth: int = 0, offset: int = 0) -> lsp.Position:
    """The position of the `nth` occurrence of `needle` in `path` (plus `offset` characters)."""
    text = path.read_text(encoding="utf-8")
    at = -1
    for _ in range(nth + 1):
        at = text.index(needle, at + 1)
    at += offset
    line = text.count("\n", 0, at)
    col = at - (text.rfind("\n", 0, at) + 1)
    return lsp.Position(line, col)


def doc(path: Path) -> lsp.TextDocumentIdentifier:
    return lsp.TextDocumentIdentifier(uri=path.resolve().as_uri())


async def open_file(client: LanguageClient, path: Path, language: str = "structured-text") -> list:
    """Open `path` and wait for its diagnostics."""
    uri = path.resolve().as_uri()
    client.text_document_did_open(lsp.DidOpenTextDocumentParams(
        lsp.TextDocumentItem(uri=uri, language_id=language, version=1, text=path.read_text(encoding="utf-8"))))
    while uri not in client.diagnostics:
        await client.wait_for_notification(lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    return client.diagnostics[uri]


def text_at(path: Path, rng: lsp.Range) -> str:
    lines = path.read_text(encoding="utf-8").splitlines()
    assert rng.start.line == rng.end.line
    return lines[rng.start.line][rng.start.character:rng.end.character]
