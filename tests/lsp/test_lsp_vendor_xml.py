"""The language features inside TwinCAT (.TcPOU/.TcDUT/.TcGVL/.TcIO) and PLCopen XML files:
positions are the XML file's own lines and columns, inside the CDATA (tests/lsp/fixtures)."""

from __future__ import annotations

import pytest
from lsprotocol import types as lsp

from lsp_helpers import FIXTURES, doc, open_file, position, text_at

pytestmark = pytest.mark.asyncio(loop_scope="module")

TC = FIXTURES / "twincat"
MAIN = TC / "POUs" / "MAIN.TcPOU"
COUNTER = TC / "POUs" / "FB_Counter.TcPOU"
AXIS_ITF = TC / "POUs" / "I_Axis.TcIO"
STATE = TC / "DUTs" / "E_State.TcDUT"
GVL = TC / "GVLs" / "GVL_Main.TcGVL"
PLCOPEN = FIXTURES / "plcopen" / "Conveyor.xml"


async def test_twincat_project_opens_without_errors(client):
    assert [d.message for d in await open_file(client, MAIN, "xml")] == []


async def test_hover_and_definition_of_an_fb_output_in_another_xml_file(client):
    await open_file(client, MAIN, "xml")
    at = position(MAIN, "fbCounter.nCount", offset=10)
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(MAIN), at))
    assert "(VAR_OUTPUT) FB_Counter.nCount : INT" in hover.contents.value
    assert text_at(MAIN, hover.range) == "nCount"
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), at))
    assert locs[0].uri == COUNTER.resolve().as_uri()
    assert locs[0].range.start == position(COUNTER, "nCount  : INT")
    assert text_at(COUNTER, locs[0].range) == "nCount"


async def test_hover_of_the_fb_type_shows_its_comment_from_the_cdata(client):
    await open_file(client, MAIN, "xml")
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(MAIN), position(MAIN, "FB_Counter;")))
    assert "FUNCTION_BLOCK FB_Counter(bEnable : BOOL; nStep : INT) => (nCount : INT)" in hover.contents.value
    assert "counts by nStep while enabled" in hover.contents.value


async def test_qualified_enum_and_gvl_names(client):
    await open_file(client, MAIN, "xml")
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), position(MAIN, "eDone")))
    assert locs[0].uri == STATE.resolve().as_uri() and text_at(STATE, locs[0].range) == "eDone"
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), position(MAIN, "nStep);")))
    assert locs[0].uri == GVL.resolve().as_uri() and text_at(GVL, locs[0].range) == "nStep"


async def test_interface_method_and_property_in_a_tcio(client):
    await open_file(client, MAIN, "xml")
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), position(MAIN, "MoveTo(")))
    assert locs[0].uri == AXIS_ITF.resolve().as_uri()
    assert locs[0].range.start == position(AXIS_ITF, "MoveTo : BOOL")
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(MAIN), position(MAIN, "iAxis.Position", offset=6)))
    assert "PROPERTY I_Axis.Position : LREAL" in hover.contents.value


async def test_completion_inside_cdata(client):
    await open_file(client, MAIN, "xml")
    result = await client.text_document_completion_async(lsp.CompletionParams(
        doc(MAIN), position(MAIN, "fbCounter.nCount >= 4", offset=10)))
    labels = {i.label for i in result.items}
    assert {"bEnable", "nStep", "nCount"} <= labels
    result = await client.text_document_completion_async(lsp.CompletionParams(
        doc(MAIN), position(MAIN, "iAxis.MoveTo", offset=6)))
    assert {"MoveTo", "Position"} <= {i.label for i in result.items}


async def test_references_and_rename_across_xml_files(client):
    await open_file(client, COUNTER, "xml")
    refs = await client.text_document_references_async(lsp.ReferenceParams(
        text_document=doc(COUNTER), position=position(COUNTER, "nCount  : INT"),
        context=lsp.ReferenceContext(include_declaration=True)))
    assert sorted({r.uri.rsplit("/", 1)[-1] for r in refs}) == ["FB_Counter.TcPOU", "MAIN.TcPOU"]
    assert len(refs) == 6
    edit = await client.text_document_rename_async(lsp.RenameParams(doc(COUNTER), position(COUNTER, "nCount  : INT"), "nTotal"))
    for uri, edits in edit.changes.items():
        path = MAIN if uri.endswith("MAIN.TcPOU") else COUNTER
        assert all(text_at(path, e.range) == "nCount" for e in edits)


async def test_typing_an_error_in_cdata_is_reported_at_its_xml_line(client):
    await open_file(client, MAIN, "xml")
    uri = MAIN.resolve().as_uri()
    original = MAIN.read_text(encoding="utf-8")
    broken = original.replace("stData.sName := 'counter';", "stData.sName := nUnknown;")
    client.text_document_did_change(lsp.DidChangeTextDocumentParams(
        lsp.VersionedTextDocumentIdentifier(version=2, uri=uri), [lsp.TextDocumentContentChangeWholeDocument(text=broken)]))
    for _ in range(20):
        await client.wait_for_notification(lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        diags = client.diagnostics.get(uri, [])
        if diags:
            break
    assert "nUnknown" in diags[0].message
    assert diags[0].range.start == position(MAIN, "'counter'")
    client.text_document_did_change(lsp.DidChangeTextDocumentParams(
        lsp.VersionedTextDocumentIdentifier(version=3, uri=uri), [lsp.TextDocumentContentChangeWholeDocument(text=original)]))
    for _ in range(20):
        await client.wait_for_notification(lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        if not client.diagnostics.get(uri):
            break
    assert not client.diagnostics.get(uri)


async def test_plcopen_xml_declarations_and_bodies(client):
    assert [d.message for d in await open_file(client, PLCOPEN, "xml")] == []
    # a use inside <xhtml> with an entity before it (`nIn &gt; nMax`): still the right column
    at = position(PLCOPEN, "nIn &gt; nMax", offset=len("nIn &gt; "))
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(PLCOPEN), at))
    assert "(VAR_INPUT) Clamp.nMax" in hover.contents.value
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(PLCOPEN), at))
    assert locs[0].range.start == position(PLCOPEN, 'variable name="nMax"', offset=len('variable name="'))
    symbols = await client.text_document_document_symbol_async(lsp.DocumentSymbolParams(doc(PLCOPEN)))
    assert {"E_Mode", "ST_Item", "Clamp", "FB_Belt", "PLC_PRG"} <= {s.name for s in symbols}
