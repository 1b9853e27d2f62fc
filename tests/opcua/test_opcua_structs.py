"""Structured DataTypes for STRUCTs: the DataType node with its StructureDefinition and binary
encoding, and the ExtensionObject variable of each struct instance, read by asyncua's client
after `load_data_type_definitions()` (in another process, so the classes come from the
server's definitions and not from this process's registry) and written back."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from asyncua import Client, ua
from opcua_helpers import ROOT, Running, run_async

import stvm

FILES = [str(Path(__file__).parent / "fixtures" / "Arrays.st")]
LIMITS = {"Home.X": {"min": -10, "max": 10}}

CLIENT = textwrap.dedent("""
    import asyncio, json, sys
    from asyncua import Client, ua
    url, uri = sys.argv[1], sys.argv[2]
    async def main():
        # a generous watchdog: the definitions are hundreds of requests, and a loaded test
        # machine answers the watchdog's probe behind them
        async with Client(url, timeout=60, watchdog_intervall=60) as client:
            ns = await client.get_namespace_index(uri)
            loaded = await client.load_data_type_definitions()
            home = await client.get_node(f"ns={ns};s=Home.@Value").read_value()
            path = await client.get_node(f"ns={ns};s=Path[1].@Value").read_value()
            print(json.dumps({"loaded": sorted(loaded), "home": [type(home).__name__, home.X, home.Y, home.Tag],
                              "path": [type(path).__name__, path.X, path.Tag]}))
    asyncio.run(main())
""")


@pytest.fixture(scope="module")
def structs_project():
    return stvm.load(FILES)


@pytest.fixture
def structs(structs_project):
    run = Running(structs_project, demo=False, files=FILES, limits=LIMITS)
    yield run
    run.close()


def test_datatype_node_definition_and_encoding(structs):
    async def body():
        async with Client(structs.url) as client:
            ns = await client.get_namespace_index(structs.ns_uri)
            dtype = client.get_node(ua.NodeId("@Type.Point", ns))
            assert (await dtype.read_browse_name()).Name == "Point"
            assert await dtype.read_node_class() == ua.NodeClass.DataType
            [parent] = await dtype.get_referenced_nodes(ua.ObjectIds.HasSubtype, ua.BrowseDirection.Inverse)
            assert parent.nodeid == ua.NodeId(ua.ObjectIds.Structure)
            definition = await dtype.read_data_type_definition()
            assert [(f.Name, f.DataType, f.ValueRank) for f in definition.Fields] == [
                ("X", ua.NodeId(ua.ObjectIds.Float), -1), ("Y", ua.NodeId(ua.ObjectIds.Float), -1),
                ("Tag", ua.NodeId(ua.ObjectIds.String), -1)]
            [encoding] = await dtype.get_referenced_nodes(ua.ObjectIds.HasEncoding)
            assert (await encoding.read_browse_name()).Name == "Default Binary"
            assert definition.DefaultEncodingId == encoding.nodeid
            home = await client.get_node(ua.NodeId("Home", ns)).get_child(f"{ns}:Value")
            assert home.nodeid == ua.NodeId("Home.@Value", ns)
            assert await home.read_data_type() == dtype.nodeid and await home.read_value_rank() == -1
            # the object view stays
            assert await client.get_node(ua.NodeId("Home.X", ns)).read_value() == 1.5
    run_async(body())


def test_a_client_in_another_process_loads_the_definitions_and_reads_the_structs(structs):
    done = subprocess.run([sys.executable, "-c", CLIENT, structs.url, structs.ns_uri], capture_output=True,
                          text=True, timeout=240, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert "Point" in result["loaded"]
    assert result["home"] == ["Point", 1.5, 2.5, "home"]
    assert result["path"] == ["Point", 0.0, ""]


def test_write_a_struct_value(structs):
    async def body():
        async with Client(structs.url) as client:
            ns = await client.get_namespace_index(structs.ns_uri)
            await client.load_data_type_definitions()
            point = ua.extension_objects_by_datatype[ua.NodeId("@Type.Point", ns)]
            home = client.get_node(ua.NodeId("Home.@Value", ns))
            await home.write_value(ua.Variant(point(X=3.0, Y=-4.0, Tag="dock"), ua.VariantType.ExtensionObject))
            assert (structs.vm["Home.X"], structs.vm["Home.Y"], structs.vm["Home.Tag"]) == (3.0, -4.0, b"dock")
            assert await home.read_value() == point(X=3.0, Y=-4.0, Tag="dock")

            async def write(variant, index_range=None):
                [status] = await client.uaclient.write(ua.WriteParameters(NodesToWrite=[ua.WriteValue(
                    NodeId=home.nodeid, AttributeId=ua.AttributeIds.Value, IndexRange=index_range,
                    Value=ua.DataValue(variant))]))
                return status.value
            # each member is checked as its own variable: the limits table, STRING[20]'s length
            assert await write(ua.Variant(point(X=11.0, Y=0.0, Tag=""), ua.VariantType.ExtensionObject)) == \
                ua.StatusCodes.BadOutOfRange
            assert await write(ua.Variant(point(X=1.0, Y=0.0, Tag="x" * 30), ua.VariantType.ExtensionObject)) == \
                ua.StatusCodes.BadOutOfRange
            assert await write(ua.Variant(5.0, ua.VariantType.Float)) == ua.StatusCodes.BadTypeMismatch
            assert await write(ua.Variant(point(X=1.0, Y=0.0, Tag=""), ua.VariantType.ExtensionObject), "0") == \
                ua.StatusCodes.BadWriteNotSupported
            assert structs.vm["Home.X"] == 3.0          # nothing of a refused write is applied
    run_async(body())
