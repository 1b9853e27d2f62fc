"""The language features on the thesis project (st_src/, its stvm.toml: twelve files, namespaced
types, Omron pin aliases), through the protocol."""

from __future__ import annotations

import pytest
from lsprotocol import types as lsp

from lsp_helpers import ROOT, doc, open_file, position, text_at

pytestmark = pytest.mark.asyncio(loop_scope="module")

ST = ROOT / "st_src"
PNP = ST / "PnP_Example.st"
TYPES = ST / "CBT_Commands_Lib_Types.st"
MOVE = ST / "CBT_MoveAbsolute.st"


async def test_the_project_opens_with_lint_warnings_only(client):
    diags = await open_file(client, PNP)
    assert all(d.severity == lsp.DiagnosticSeverity.Warning for d in diags)
    # the other files of the project got theirs too (MoveAbsolute has lint findings)
    assert client.diagnostics.get(MOVE.resolve().as_uri())


async def test_hover_on_an_fb_instance(client):
    await open_file(client, PNP)
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(PNP), position(PNP, "Timer_1(In")))
    assert "(VAR) PnP_Example.Timer_1 : TON" in hover.contents.value
    assert "instance called at thesis line 7726" in hover.contents.value


async def test_definition_of_a_namespaced_type_and_an_output_pin(client):
    await open_file(client, PNP)
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(PNP), position(PNP, "stCBT_Connection;")))
    assert locs[0].uri == TYPES.resolve().as_uri() and text_at(TYPES, locs[0].range) == "stCBT_Connection"
    locs = await client.text_document_definition_async(lsp.DefinitionParams(doc(PNP), position(PNP, "Done =>MoveDone")))
    assert locs[0].uri == MOVE.resolve().as_uri() and text_at(MOVE, locs[0].range) == "Done"


async def test_omron_pin_alias_goes_to_the_iec_pin(client):
    await open_file(client, PNP)
    hover = await client.text_document_hover_async(lsp.HoverParams(doc(PNP), position(PNP, "In:=Timer_Enable")))
    assert "(VAR_INPUT) TON.IN : BOOL" in hover.contents.value


async def test_global_references_include_var_external_declarations(client):
    await open_file(client, PNP)
    refs = await client.text_document_references_async(lsp.ReferenceParams(
        text_document=doc(PNP), position=position(PNP, "CBT :=Cobot,\n", offset=6),
        context=lsp.ReferenceContext(include_declaration=True)))
    files = {r.uri.rsplit("/", 1)[-1] for r in refs}
    assert {"Globals.st", "PnP_Example.st", "Program_Example.st"} <= files


async def test_completion_of_a_struct_and_an_fb(client):
    await open_file(client, PNP)
    result = await client.text_document_completion_async(lsp.CompletionParams(doc(PNP), position(PNP, "Timer_1.Q", offset=8)))
    assert {"IN", "PT", "Q", "ET"} <= {i.label for i in result.items}
    result = await client.text_document_completion_async(lsp.CompletionParams(
        doc(PNP), position(PNP, "CBT_MoveAbsolute_Instance(", offset=len("CBT_MoveAbsolute_Instance("))))
    labels = {i.label for i in result.items}
    assert "Cobot" in labels and "Prg_Step" in labels


async def test_signature_help_with_named_pins(client):
    await open_file(client, PNP)
    help = await client.text_document_signature_help_async(lsp.SignatureHelpParams(
        doc(PNP), position(PNP, "Busy =>MoveBusy", offset=5)))
    sig = help.signatures[0]
    assert sig.label.startswith("CBT_MoveAbsolute(")
    active = sig.parameters[help.active_parameter].label
    assert sig.label[active[0]:active[1]].startswith("Busy =>")
