"""Renaming an interface's METHOD renames its implementation in every FB that IMPLEMENTS the
interface (directly or through a base FB), the overrides and every call, through the protocol;
a name that clashes in any of those FBs is refused (tests/lsp/fixtures/oo_rename)."""

from __future__ import annotations

import re

import pytest
from lsprotocol import types as lsp

from core_helpers import cli
from lsp_helpers import FIXTURES, doc, open_file, position, text_at

pytestmark = pytest.mark.asyncio(loop_scope="module")

FOLDER = FIXTURES / "oo_rename"
DRIVES, MAIN = FOLDER / "drives.st", FOLDER / "main.st"


def occurrences(path, word: str) -> set[tuple[int, int]]:
    return {(text.count("\n", 0, m.start()), m.start() - (text.rfind("\n", 0, m.start()) + 1))
            for text in [path.read_text(encoding="utf-8")] for m in re.finditer(rf"\b{word}\b", text)}


def apply(path, edits: list[lsp.TextEdit]) -> str:
    lines = path.read_text(encoding="utf-8").split("\n")
    for e in sorted(edits, key=lambda e: (e.range.start.line, e.range.start.character), reverse=True):
        line = lines[e.range.start.line]
        lines[e.range.start.line] = line[:e.range.start.character] + e.new_text + line[e.range.end.character:]
    return "\n".join(lines)


async def rename(client, path, needle: str, nth: int, new_name: str) -> dict:
    edit = await client.text_document_rename_async(lsp.RenameParams(
        text_document=doc(path), position=position(path, needle, nth=nth), new_name=new_name))
    return {uri.rsplit("/", 1)[-1]: edits for uri, edits in edit.changes.items()}


async def test_renaming_the_interface_method_renames_every_implementation_and_call(client, tmp_path):
    await open_file(client, MAIN)
    changes = await rename(client, DRIVES, "Start", 0, "Run")     # the interface's declaration
    assert set(changes) == {"drives.st", "main.st"}
    for path in (DRIVES, MAIN):
        edits = changes[path.name]
        assert {text_at(path, e.range) for e in edits} == {"Start"} and {e.new_text for e in edits} == {"Run"}
        # every `Start` of the project is the method: the interface's, the three FBs' (their
        # result variable too), SUPER^.Start and the calls through the interface and the FBs
        assert {(e.range.start.line, e.range.start.character) for e in edits} == occurrences(path, "Start")
    # the renamed project checks clean
    for path in (DRIVES, MAIN):
        (tmp_path / path.name).write_text(apply(path, changes[path.name]), encoding="utf-8")
    rc, _, err = cli(["check", str(tmp_path)])
    assert rc == 0, err


async def test_renaming_an_implementation_renames_the_interface_and_the_others(client):
    await open_file(client, MAIN)
    from_fb = await rename(client, DRIVES, "Start", 3, "Run")      # FB_Pump's METHOD Start
    from_call = await rename(client, MAIN, "Start", 1, "Run")      # pump.Start(...)
    from_itf = await rename(client, DRIVES, "Start", 0, "Run")
    key = lambda changes: {f: sorted((e.range.start.line, e.range.start.character) for e in es)  # noqa: E731
                           for f, es in changes.items()}
    assert key(from_fb) == key(from_call) == key(from_itf)


async def test_a_name_that_clashes_in_one_implementing_fb_is_refused(client):
    await open_file(client, MAIN)
    # FB_Pump has a variable Launch: its Start cannot become Launch, so the interface's cannot
    with pytest.raises(Exception, match="'Launch' is already declared in FB_Pump"):
        await rename(client, DRIVES, "Start", 0, "Launch")
    with pytest.raises(Exception, match="already declared"):
        await rename(client, MAIN, "Start", 0, "Launch")


async def test_other_methods_are_still_renamed_alone(client):
    await open_file(client, MAIN)
    changes = await rename(client, DRIVES, "running", 0, "isRunning")
    assert set(changes) == {"drives.st"} and len(changes["drives.st"]) == 3
