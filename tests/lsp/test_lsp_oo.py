"""The language features on an object-oriented ST project of three files (tests/lsp/fixtures/oo:
types, an interface with an FB implementing it, a program using both), through the protocol."""

from __future__ import annotations

import pytest
from lsprotocol import types as lsp

from lsp_helpers import FIXTURES, doc, open_file, position, text_at

pytestmark = pytest.mark.asyncio(loop_scope="module")

OO = FIXTURES / "oo"
MAIN, AXIS, TYPES = OO / "main.st", OO / "axis.st", OO / "types.st"


async def test_open_publishes_no_errors_for_the_project(client):
    assert list(await open_file(client, MAIN)) == []


async def test_hover_shows_type_comment_and_declaration(client):
    await open_file(client, MAIN)
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(MAIN), position(MAIN, "delay(")))
    text = hover.contents.value
    assert "(VAR) Main.delay : TON" in text
    assert "waits before the lamp turns blue" in text      # the declaration's comment
    assert "line 5" in text
    assert "FUNCTION_BLOCK TON(IN : BOOL; PT : TIME) => (Q : BOOL; ET : TIME)" in text
    assert text_at(MAIN, hover.range) == "delay"


async def test_hover_on_function_shows_signature_and_doc(client):
    await open_file(client, MAIN)
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(MAIN), position(MAIN, "Scale(", offset=2)))
    assert "FUNCTION Scale(value : REAL; factor : REAL) : REAL" in hover.contents.value
    assert "Scales a value by a factor." in hover.contents.value


async def test_hover_on_a_stdlib_fb_shows_its_documentation(client):
    await open_file(client, MAIN)
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(MAIN), position(MAIN, "TON;")))
    text = hover.contents.value
    assert "FUNCTION_BLOCK TON(IN : BOOL; PT : TIME) => (Q : BOOL; ET : TIME)" in text
    assert "Timers: IN, PT -> Q, ET on the VM clock" in text      # the comment above it in iec_standard.st
    assert "stvm standard library" in text


async def test_hover_on_struct_field_across_files(client):
    await open_file(client, MAIN)
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(MAIN), position(MAIN, "point.x", offset=6)))
    assert "ST_Point.x : REAL" in hover.contents.value
    assert "metres along the belt" in hover.contents.value


async def test_definition_across_files_and_through_the_interface(client):
    await open_file(client, MAIN)
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), position(MAIN, "MoveTo(target")))
    assert len(locs) == 1 and locs[0].uri == AXIS.resolve().as_uri()
    assert locs[0].range.start == position(AXIS, "MoveTo : BOOL")          # the interface's method
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), position(MAIN, "ST_Point")))
    assert locs[0].uri == TYPES.resolve().as_uri() and text_at(TYPES, locs[0].range) == "ST_Point"
    # the pin of a method call: the method's input
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), position(MAIN, "target :=")))
    assert locs[0].range.start == position(AXIS, "target : REAL")


async def test_definition_into_the_stdlib(client):
    await open_file(client, MAIN)
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), position(MAIN, "TON;")))
    assert len(locs) == 1 and locs[0].uri.endswith("/iec_standard.st")
    from urllib.parse import unquote, urlparse
    stdlib_text = open(unquote(urlparse(locs[0].uri).path), encoding="utf-8").read().splitlines()
    assert "FUNCTION_BLOCK TON" in stdlib_text[locs[0].range.start.line]
    # the pin IN of TON, from the call
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(MAIN), position(MAIN, "IN :=")))
    line = open(unquote(urlparse(locs[0].uri).path), encoding="utf-8").read().splitlines()[locs[0].range.start.line]
    assert line.strip().startswith("IN")


async def test_implementation_of_an_interface_method_and_the_interface(client):
    await open_file(client, MAIN)
    locs = await client.text_document_implementation_async(lsp.ImplementationParams(doc(MAIN), position(MAIN, "MoveTo(target")))
    assert [(loc.uri.rsplit("/", 1)[-1], loc.range.start) for loc in locs] == [("axis.st", position(AXIS, "MoveTo : BOOL", nth=1))]
    locs = await client.text_document_implementation_async(lsp.ImplementationParams(doc(MAIN), position(MAIN, "I_Axis")))
    assert [text_at(AXIS, loc.range) for loc in locs] == ["FB_Axis"]


async def test_editing_one_file_rechecks_its_dependents(client):
    await open_file(client, MAIN)
    await open_file(client, TYPES)
    main_uri, types_uri = MAIN.resolve().as_uri(), TYPES.resolve().as_uri()
    original = TYPES.read_text(encoding="utf-8")
    await _edit(client, types_uri, 2, original.replace("x : REAL;", "xpos : REAL;"))
    diags = await _diagnostics(client, main_uri, lambda d: any(x.severity == lsp.DiagnosticSeverity.Error for x in d))
    assert "ST_Point has no member 'x'" in diags[0].message and diags[0].range.start.line == 11
    await _edit(client, types_uri, 3, original)
    await _diagnostics(client, main_uri, lambda d: list(d) == [])


async def test_references_of_an_fb_variable_in_method_and_property(client):
    await open_file(client, AXIS)
    refs = await client.text_document_references_async(lsp.ReferenceParams(text_document=doc(AXIS), position=position(AXIS, "posNow"), context=lsp.ReferenceContext(include_declaration=True)))
    assert [(r.range.start.line + 1) for r in refs] == [16, 22, 27]
    assert all(text_at(AXIS, r.range) == "posNow" for r in refs)
    refs = await client.text_document_references_async(lsp.ReferenceParams(text_document=doc(AXIS), position=position(AXIS, "posNow"), context=lsp.ReferenceContext(include_declaration=False)))
    assert len(refs) == 2


async def test_references_of_a_type_across_files(client):
    await open_file(client, TYPES)
    refs = await client.text_document_references_async(lsp.ReferenceParams(text_document=doc(TYPES), position=position(TYPES, "E_Color"), context=lsp.ReferenceContext(include_declaration=True)))
    files = sorted({r.uri.rsplit("/", 1)[-1] for r in refs})
    assert files == ["main.st", "types.st"]
    assert len(refs) == 4       # declaration, the variable's type, two E_Color#… literals


async def test_completion_of_fb_members_and_interface_methods(client):
    await open_file(client, MAIN)
    # `delay.` offers TON's inputs and outputs, not its internals
    items = await _complete(client, "delay.Q", 6)
    labels = {i.label for i in items}
    assert {"IN", "PT", "Q", "ET"} <= labels
    # `drive.` (an I_Axis) offers the interface's method and property
    items = await _complete(client, "drive.Position", 6)
    labels = {i.label for i in items}
    assert {"MoveTo", "Position"} <= labels
    assert any(i.insert_text == "MoveTo(target := ${1})$0" for i in items)


async def test_completion_of_enum_values_and_scope(client):
    await open_file(client, MAIN)
    items = await _complete(client, "E_Color#Blue", 8)
    assert [i.label for i in items] == ["Red", "Green", "Blue"]
    items = await _complete(client, "reading := drive", 0)
    labels = {i.label for i in items}
    assert {"axis", "drive", "delay", "point", "lamp", "reading", "Scale", "IF"} <= labels
    assert "TON" not in labels       # the stdlib's names once a letter is typed
    typed = await _complete(client, "reading := drive", 3)      # `rea|`
    assert {i.label for i in typed} >= {"reading", "REAL"} and "axis" not in {i.label for i in typed}
    assert "TON" in {i.label for i in await _complete(client, "TON;", 2)}
    snippets = {i.label: i.insert_text for i in items if i.kind == lsp.CompletionItemKind.Snippet}
    assert snippets["delay(IN := , PT := )"] == "delay(IN := ${1}, PT := ${2})$0"
    assert snippets["Scale(value := , factor := )"] == "Scale(value := ${1}, factor := ${2})$0"


async def _complete(client, needle: str, offset: int):
    result = await client.text_document_completion_async(lsp.CompletionParams(doc(MAIN), position(MAIN, needle, offset=offset)))
    return result.items if isinstance(result, lsp.CompletionList) else result


async def test_signature_help_inside_a_call(client):
    await open_file(client, MAIN)
    help = await client.text_document_signature_help_async(lsp.SignatureHelpParams(
        doc(MAIN), position(MAIN, "PT := T#1s", offset=6)))
    sig = help.signatures[0]
    assert sig.label.startswith("TON(IN := BOOL, PT := TIME, Q => BOOL, ET => TIME")
    assert help.active_parameter == 1


async def test_rename_variable_everywhere_and_refuse_clash_and_stdlib(client):
    await open_file(client, AXIS)
    edit = await client.text_document_rename_async(lsp.RenameParams(doc(AXIS), position(AXIS, "posNow", nth=1), "actual"))
    spots = edit.changes[AXIS.resolve().as_uri()]
    assert sorted(e.range.start.line + 1 for e in spots) == [16, 22, 27] and {e.new_text for e in spots} == {"actual"}
    # the method input `target` of MoveTo cannot become the FB's `posNow`
    with pytest.raises(Exception, match="already declared"):
        await client.text_document_rename_async(lsp.RenameParams(doc(AXIS), position(AXIS, "target", nth=1), "posNow"))
    await open_file(client, MAIN)
    with pytest.raises(Exception, match="standard library"):
        await client.text_document_rename_async(lsp.RenameParams(doc(MAIN), position(MAIN, "TON;"), "Timer"))
    with pytest.raises(Exception, match="keyword"):
        await client.text_document_rename_async(lsp.RenameParams(doc(MAIN), position(MAIN, "reading :"), "END_IF"))


async def test_rename_across_files(client):
    await open_file(client, MAIN)
    edit = await client.text_document_rename_async(lsp.RenameParams(doc(MAIN), position(MAIN, "Scale("), "Scaled"))
    assert {uri.rsplit("/", 1)[-1]: len(edits) for uri, edits in edit.changes.items()} == {"main.st": 1, "axis.st": 2}


async def test_document_and_workspace_symbols(client):
    await open_file(client, AXIS)
    symbols = await client.text_document_document_symbol_async(lsp.DocumentSymbolParams(doc(AXIS)))
    top = {s.name: s for s in symbols}
    assert {"I_Axis", "FB_Axis", "Scale"} <= set(top)
    fb = top["FB_Axis"]
    assert {c.name for c in fb.children} >= {"posNow", "MoveTo", "Position"}
    found = await client.workspace_symbol_async(lsp.WorkspaceSymbolParams(query="axis"))
    assert {s.name for s in found} >= {"I_Axis", "FB_Axis"}


async def test_semantic_tokens_and_folding(client):
    await open_file(client, MAIN)
    tokens = await client.text_document_semantic_tokens_full_async(lsp.SemanticTokensParams(doc(MAIN)))
    data = list(tokens.data)
    assert len(data) % 5 == 0 and len(data) > 50
    # the first token is the program's name, a declaration
    assert data[:2] == [0, 8] and data[2] == len("Main") and data[4] & 1
    folds = await client.text_document_folding_range_async(lsp.FoldingRangeParams(doc(MAIN)))
    assert (0, 17) in {(f.start_line, f.end_line) for f in folds}      # PROGRAM … END_PROGRAM
    assert (14, 16) in {(f.start_line, f.end_line) for f in folds}     # IF … END_IF


async def test_typing_an_error_is_reported_then_cleared(client):
    await open_file(client, MAIN)
    uri = MAIN.resolve().as_uri()
    original = MAIN.read_text(encoding="utf-8")
    broken = original.replace("reading := drive.Position + point.x;", "reading := drive.Position + point.z;")
    await _edit(client, uri, 2, broken)
    diags = await _diagnostics(client, uri, lambda d: any(x.severity == lsp.DiagnosticSeverity.Error for x in d))
    assert any("z" in d.message for d in diags) and diags[0].range.start.line == 11
    await _edit(client, uri, 3, original)
    await _diagnostics(client, uri, lambda d: list(d) == [])


async def _edit(client, uri: str, version: int, text: str) -> None:
    client.text_document_did_change(lsp.DidChangeTextDocumentParams(
        lsp.VersionedTextDocumentIdentifier(version=version, uri=uri),
        [lsp.TextDocumentContentChangeWholeDocument(text=text)]))


async def _diagnostics(client, uri: str, ready):
    for _ in range(20):
        await client.wait_for_notification(lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        if ready(client.diagnostics.get(uri, [])):
            return client.diagnostics[uri]
    raise AssertionError(f"no such diagnostics for {uri}: {client.diagnostics.get(uri)}")
