"""Which variables are published and writable: the [opcua] rules over the variable catalog."""

import pytest
from asyncua import Client, ua
from opcua_helpers import Running, run_async

import stvm
from stvm.frontend import catalog
from stvm.opcua.config import OpcUaConfigError, load_config
from stvm.opcua.nodes import select

SOURCE = """
TYPE Pt : STRUCT x : REAL; y : REAL; END_STRUCT; END_TYPE
VAR_GLOBAL g : INT; pts : ARRAY[1..2] OF Pt; timer : TON; END_VAR
VAR_GLOBAL CONSTANT LIMIT : INT := 3; END_VAR
PROGRAM Main
VAR_INPUT speed : INT; END_VAR
VAR_OUTPUT busy : BOOL; END_VAR
VAR count : DINT; t1 : TON; END_VAR
count := count + speed;
t1(IN := busy, PT := T#1s);
END_PROGRAM
"""


@pytest.fixture(scope="module")
def vm(tmp_path_factory):
    path = tmp_path_factory.mktemp("nodes") / "main.st"
    path.write_text(SOURCE)
    return stvm.load([str(path)]).start()


def chosen(vm, **table):
    selection = select(catalog(vm), load_config({"opcua": table}, None, ["main.st"], None))
    return {path for path in selection.variables}, {p for p, v in selection.variables.items() if v.writable}


def test_default_publishes_globals_and_program_variables_not_fb_internals(vm):
    published, writable = chosen(vm)
    assert published == {"g", "pts[1].x", "pts[1].y", "pts[2].x", "pts[2].y", "LIMIT",
                         "Main.speed", "Main.busy", "Main.count"}
    assert writable == {"g", "pts[1].x", "pts[1].y", "pts[2].x", "pts[2].y", "Main.speed"}   # no constant


def test_sets_patterns_exclude_and_read_only(vm):
    published, writable = chosen(vm, publish=["@globals", "@fb_internals"], exclude=["pts[2]"],
                                 writable=["Main.t1.PT", "pts[*].x", "timer.IN"], read_only=["pts[1].x"])
    assert "Main.t1.ET" in published and "timer.Q" in published and "Main.count" not in published
    assert not any(p.startswith("pts[2]") for p in published)
    assert writable == {"Main.t1.PT", "timer.IN"}
    published, _ = chosen(vm, publish=["Main.**"])
    assert "Main.t1.Q" in published and "g" not in published   # a pattern covers FB members below it


@pytest.mark.parametrize("table, message", [
    ({"publish": ["Mian.*"]}, "publish: 'Mian.\\*' matches no variable"),
    ({"exclude": ["nothing"]}, "exclude: 'nothing' matches no variable"),
    ({"writable": ["Main.nope"]}, "writable: 'Main.nope' matches no variable"),
])
def test_rules_that_match_nothing_are_errors(vm, table, message):
    with pytest.raises(OpcUaConfigError, match=message):
        chosen(vm, **table)


def test_all_thesis_variables_with_fb_internals(thesis_project):
    """~7,000 variables (the FB instances' socket buffers included) serve and read like the rest."""
    run = Running(thesis_project, {"publish": ["@globals", "@programs", "@fb_internals"]}, demo=False)
    try:
        assert len(run.server.variables) > 7000

        async def body():
            async with Client(run.url) as client:
                ns = await client.get_namespace_index(run.ns_uri)
                fb = client.get_node(ua.NodeId("PnP_Example_Instance.CBT_MoveAbsolute_Instance", ns))
                assert await fb.read_node_class() == ua.NodeClass.Object
                names = {(await c.read_browse_name()).Name for c in await fb.get_children()}
                assert {"Execute", "Busy", "FB_step"} <= names
                step = client.get_node(ua.NodeId("PnP_Example_Instance.CBT_MoveAbsolute_Instance.FB_step", ns))
                assert isinstance(await step.read_value(), int)
                assert ua.AccessLevel.CurrentWrite not in await step.get_access_level()   # FB internals: read only
        run_async(body())
    finally:
        run.close()
