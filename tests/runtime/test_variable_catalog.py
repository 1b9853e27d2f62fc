"""The one variable catalog (stvm/runtime/catalog.py): every front end lists the same variables in
the same order.

The same two projects (the thesis `st_src` project and an object-oriented TwinCAT-style program
with inheritance, an interface, methods, a property, arrays of one and two dimensions, nested
structs, an array of FB instances, a VAR_IN_OUT, a VAR_TEMP, a VAR_EXTERNAL, REFERENCE TO,
POINTER TO and REF_TO) are listed through the trace's watch globs, `stvm dap` (a real DAP session
expanding every variable), the debugger console's `info variables`, the debugger's instance paths,
the HMI's catalog and an OPC UA client's browse of the server's address space. Each front end
presents the catalog its own way (the trace records elementary values only, OPC UA publishes
values with a UA data type and the nodes above them, DAP groups a two-dimensional array by rows),
which the comparisons allow for; the set and the order are the catalog's.
"""

from __future__ import annotations

import asyncio
import io
from pathlib import Path

import pytest

import stvm
from core_helpers import write_st
from stvm.debug.build import load_debug
from stvm.debug.console import Console
from stvm.debug.engine import Engine
from stvm.frontend import VariableBridge, catalog as hmi_catalog
from stvm.opcua.datatypes import ua_type
from stvm.project import Options, resolve
from stvm.runtime.catalog import ELEMENTARY_KINDS, MAX_ARRAY_ELEMENTS, Catalog
from stvm.semantics import types as t
from stvm.trace.signals import select_signals

ROOT = Path(__file__).resolve().parents[2]
THESIS = ROOT / "st_src" / "PnP_Example.st"

OO_SOURCE = """\
TYPE E_Mode : (Idle, Run, Fault); END_TYPE

TYPE ST_Point :
STRUCT
    x, y : REAL;
END_STRUCT
END_TYPE

TYPE ST_Job :
STRUCT
    id : DINT;
    target : ST_Point;
    path : ARRAY[1..3] OF ST_Point;
    mode : E_Mode;
END_STRUCT
END_TYPE

INTERFACE I_Axis
METHOD Move : BOOL
VAR_INPUT pos : REAL; END_VAR
END_METHOD
PROPERTY Position : REAL
GET
END_GET
END_PROPERTY
END_INTERFACE

FUNCTION_BLOCK FB_Base
VAR_INPUT bEnable : BOOL; END_VAR
VAR_OUTPUT bBusy : BOOL; nErrorId : UDINT; END_VAR
VAR nCalls : INT; END_VAR
nCalls := nCalls + 1;
bBusy := bEnable;
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Axis EXTENDS FB_Base IMPLEMENTS I_Axis
VAR_IN_OUT job : ST_Job; END_VAR
VAR_OUTPUT fPos : REAL; END_VAR
VAR
    fTarget : REAL;
    history : ARRAY[0..2] OF REAL;
    trig : R_TRIG;
END_VAR
VAR_TEMP scratch : INT; END_VAR
VAR CONSTANT fMax : REAL := 100.0; END_VAR
SUPER^();
scratch := 1;
trig(CLK := bEnable);
fPos := fPos + (fTarget - fPos) / 2.0;
history[nCalls MOD 3] := fPos;
job.target.x := fPos;

METHOD Move : BOOL
VAR_INPUT pos : REAL; END_VAR
fTarget := pos;
Move := TRUE;
END_METHOD

PROPERTY Position : REAL
GET
Position := fPos;
END_GET
END_PROPERTY
END_FUNCTION_BLOCK

VAR_GLOBAL
    gJob : ST_Job;
    gGrid : ARRAY[1..2, 1..3] OF INT;
    gMode : E_Mode := E_Mode.Run;
    gCount : UINT;
END_VAR

VAR_GLOBAL CONSTANT
    cLimit : INT := 7;
END_VAR

PROGRAM MAIN
VAR
    axis : FB_Axis;
    axes : ARRAY[1..2] OF FB_Base;
    itf : I_Axis;
    refJob : REFERENCE TO ST_Job;
    pJob : POINTER TO ST_Job;
    rCount : REF_TO UINT;
    local : ST_Job;
    grid : ARRAY[0..1, 0..1] OF BOOL;
    done : BOOL;
END_VAR
VAR_EXTERNAL gCount : UINT; END_VAR
itf := axis;
refJob REF= gJob;
pJob := ADR(local);
rCount := REF(gCount);
axis(bEnable := TRUE, job := local);
done := itf.Move(12.5);
axes[1](bEnable := done);
gCount := gCount + 1;
gGrid[2, 3] := gGrid[2, 3] + 1;
END_PROGRAM
"""


@pytest.fixture(scope="module")
def oo_file(tmp_path_factory) -> Path:
    return write_st(OO_SOURCE, "oo.st", tmp_path_factory.mktemp("catalog"))


def _settings(files: list[Path], dialect: str | None):
    """The settings every command gives these files (the one driver: manifest, then --dialect)."""
    return resolve([str(f) for f in files], Options(dialect=dialect)).settings


@pytest.fixture(scope="module", params=["thesis", "oo"])
def project(request, oo_file):
    """(files, dialect, loaded project, a VM after 3 scans, the catalog's paths in order)."""
    files, dialect = ([THESIS], None) if request.param == "thesis" else ([oo_file], "twincat")
    loaded = stvm.load([str(f) for f in files], _settings(files, dialect))
    vm = loaded.start(scan="1ms")
    vm.run(cycles=3)
    paths = [node.path for node in Catalog(vm).walk()]
    yield files, dialect, loaded, vm, paths
    vm.close()


def _elementary(vm) -> list[str]:
    return [node.path for node in Catalog(vm).walk() if node.type.kind in ELEMENTARY_KINDS]


def test_order_and_skip_rules_on_the_oo_program(oo_file):
    loaded = stvm.load([str(oo_file)], _settings([oo_file], "twincat"))
    vm = loaded.start(scan="1ms")
    paths = [node.path for node in Catalog(vm).walk()]
    # globals first (declaration order), then the program instance, depth first
    start = paths.index("gJob")      # (after the dialect's own globals, such as TwinCAT's constants)
    assert paths[start:start + 4] == ["gJob", "gJob.id", "gJob.target", "gJob.target.x"]
    assert paths.index("cLimit") < paths.index("MAIN") < paths.index("MAIN.axis")
    # inherited members first, then the FB's own; two dimensions row-major, written without spaces
    axis = [p for p in paths if p.startswith("MAIN.axis.")]
    assert axis[:4] == ["MAIN.axis.bEnable", "MAIN.axis.bBusy", "MAIN.axis.nErrorId", "MAIN.axis.nCalls"]
    assert [p for p in paths if p.startswith("gGrid[")] == [f"gGrid[{i},{j}]" for i in (1, 2) for j in (1, 2, 3)]
    # skipped: VAR_IN_OUT, VAR_TEMP, VAR_EXTERNAL (aliases, or alive only during a call)
    for skipped in ("MAIN.axis.job", "MAIN.axis.scratch", "MAIN.gCount"):
        assert skipped not in paths
    # references, pointers and interfaces are leaves, not followed
    for leaf in ("MAIN.itf", "MAIN.refJob", "MAIN.pJob", "MAIN.rCount"):
        assert leaf in paths and not any(p.startswith(leaf + ".") or p.startswith(leaf + "^") for p in paths)
    nodes = {node.path: node for node in Catalog(vm).walk()}
    assert nodes["MAIN.axis.fMax"].constant and nodes["cLimit"].constant and not nodes["gCount"].constant
    assert nodes["MAIN.axis.trig.Q"].in_fb and not nodes["MAIN.done"].in_fb
    vm.close()


def test_every_path_resolves_through_the_accessor(project):
    """The catalog's path syntax is the one `vm.resolve` (stvm/runtime/access.py) reads."""
    _files, _dialect, _loaded, vm, paths = project
    cat = Catalog(vm)
    for node in cat.walk():
        if node.kind == "program":
            continue
        container, key, ty = vm.resolve(node.path)
        value = container[key] if isinstance(key, int) else getattr(container, key)
        assert value is node.read() or value == node.read(), node.path
        assert ty == node.type or ty.name == node.type.name, node.path
        assert cat.node(node.path.lower()) is not None
    assert len(paths) == len(set(p.lower() for p in paths))


def test_a_huge_array_is_listed_without_its_elements(tmp_path):
    path = write_st(f"""\
PROGRAM Main
VAR big : ARRAY[1..{MAX_ARRAY_ELEMENTS + 1}] OF INT; small : ARRAY[1..2] OF INT; END_VAR
big[3] := 1;
END_PROGRAM
""", "big.st", tmp_path)
    vm = stvm.load([str(path)]).start(scan="1ms")
    assert [node.path for node in Catalog(vm).walk()] == ["Main", "Main.big", "Main.small", "Main.small[1]",
                                                          "Main.small[2]"]
    assert vm.get("Main.big[3]") == 0     # still resolves by path
    vm.close()


def test_trace_globs_record_the_catalog_leaves(project):
    _files, _dialect, _loaded, vm, _paths = project
    assert [s.name for s in select_signals(vm, ["**"])] == _elementary(vm)


def test_hmi_catalog_and_bridge_read_every_catalog_leaf(project):
    _files, _dialect, _loaded, vm, paths = project
    assert [node.path for root in hmi_catalog(vm) for node in root.walk()] == paths
    leaves = _elementary(vm)
    values = VariableBridge(vm).read_now(leaves)
    assert list(values) == leaves
    assert all(values[p] == vm.get(p) for p in leaves)


def test_debugger_console_lists_the_catalog(project):
    files, dialect, _loaded, _vm, paths = project
    build = load_debug([str(f) for f in files], _settings(files, dialect))
    engine = Engine(build)
    engine.start(stop_on_entry=True)
    try:
        assert engine.wait_started(30) is not None
        out = io.StringIO()
        console = Console(engine, stdin=io.StringIO(), stdout=out)
        console.execute("info variables")
        listed = [line.split(" : ", 1)[0] for line in out.getvalue().splitlines()]
        assert listed == paths
        out.truncate(0)
        out.seek(0)
        console.execute("info variables **.Q")      # a glob, as the trace reads it
        expected = [p for p in paths if p.lower().endswith(".q")]
        assert expected and [line.split(" : ", 1)[0] for line in out.getvalue().splitlines()] == expected
        # the instance paths a stop shows (`Main.axis`) are the catalog's FB instances
        fb_paths = {node.path for node in Catalog(engine.vm).walk() if isinstance(node.type, t.FBType)}
        assert set(engine._paths.values()) == fb_paths
    finally:
        engine.terminate()


def test_dap_shows_the_catalog(project):
    from debug.dap_client import DapClient   # lazy: the DAP client lives with the debugger's tests
    files, dialect, _loaded, _vm, paths = project
    dap = DapClient()
    try:
        args = {"stopOnEntry": True, "robot": "none"}
        if dialect:
            args["dialect"] = dialect
        dap.launch([str(f) for f in files], **args)
        assert dap.stopped("entry")
        scopes = dap.body("scopes", frameId=1)["scopes"]
        assert [s["name"] for s in scopes] == ["Globals", "Programs"]
        shown: list[str] = []

        def expand(reference: int) -> None:
            for item in dap.variables(reference).values():
                if "evaluateName" in item:          # a row of a 2-D array is DAP's presentation only
                    shown.append(item["evaluateName"])
                if item["variablesReference"]:
                    expand(item["variablesReference"])

        for scope in scopes:
            expand(scope["variablesReference"])
        assert shown == paths
    finally:
        assert dap.close() == 0


def test_opcua_browse_shows_the_catalog(project):
    from asyncua import Client, ua   # lazy: the OPC UA client only here
    from stvm.opcua import load_config
    from stvm.opcua.nodes import GLOBALS_ID
    from stvm.opcua.server import OpcUaServer
    _files, _dialect, loaded, vm, paths = project
    config = load_config({"opcua": {"start": "paused", "publish": ["@globals", "@programs", "@fb_internals"]}},
                         loaded.root, [str(f) for f in _files], "opc.tcp://127.0.0.1:0")
    server = OpcUaServer(vm, config)
    url = server.start()

    async def browse() -> list[str]:
        found: list[str] = []
        async with Client(url) as client:
            ns = await client.get_namespace_index(config.namespace_uri)

            async def visit(node) -> None:
                for child in await node.get_children(refs=ua.ObjectIds.HierarchicalReferences):
                    nid = child.nodeid
                    if nid.NamespaceIndex == ns and isinstance(nid.Identifier, str) and nid.Identifier in known:
                        found.append(nid.Identifier)
                        await visit(child)
                    elif nid.NamespaceIndex == ns and nid.Identifier == GLOBALS_ID:
                        await visit(child)
            await visit(client.nodes.objects)
        return found

    known = set(paths)
    try:
        browsed = asyncio.run(asyncio.wait_for(browse(), 120))
    finally:
        server.stop()
    nodes = {node.path: node for node in Catalog(vm).walk()}
    # in catalog order, every leaf with an OPC UA data type and the nodes above them
    assert browsed == sorted(browsed, key=paths.index)
    published = [p for p in paths if nodes[p].leaf and ua_type(nodes[p].type) is not None]
    assert [p for p in browsed if nodes[p].leaf] == published
    for p in browsed:
        assert nodes[p].leaf or any(q.startswith(p + ".") or q.startswith(p + "[") for q in published)
