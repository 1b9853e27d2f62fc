"""Array-valued variables beside the element variables, IndexRange on Read and Write (OPC UA
Part 4 §7.27), driven by asyncua's client over loopback on a small project of arrays."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest
from asyncua import Client, ua
from opcua_helpers import Running, run_async

import stvm

FILES = [str(Path(__file__).parent / "fixtures" / "Arrays.st")]
LIMITS = {"Counts[*]": {"min": -100, "max": 100}}


@pytest.fixture(scope="module")
def arrays_project():
    return stvm.load(FILES)


@pytest.fixture
def arrays(arrays_project):
    run = Running(arrays_project, demo=False, files=FILES, limits=LIMITS)
    yield run
    run.close()


def read_items(client: Client, node, *ranges: str):
    return client.uaclient.read(ua.ReadParameters(NodesToRead=[
        ua.ReadValueId(NodeId=node.nodeid, AttributeId=ua.AttributeIds.Value, IndexRange=r) for r in ranges]))


async def write_range(client: Client, node, index_range: str, variant: ua.Variant) -> ua.StatusCode:
    [status] = await client.uaclient.write(ua.WriteParameters(NodesToWrite=[ua.WriteValue(
        NodeId=node.nodeid, AttributeId=ua.AttributeIds.Value, IndexRange=index_range, Value=ua.DataValue(variant))]))
    return status


def test_array_variable_value_rank_dimensions_and_type(arrays):
    async def body():
        async with Client(arrays.url) as client:
            ns = await client.get_namespace_index(arrays.ns_uri)
            counts = await client.get_node(f"ns={ns};s=Counts").get_child(f"{ns}:Value")
            assert counts.nodeid == ua.NodeId("Counts.@Value", ns)
            assert await counts.read_value() == [1, 2, 3, 4, 5]      # OPC UA index 0 is Counts[1]
            assert await counts.read_value_rank() == 1
            assert await counts.read_array_dimensions() == [5]
            assert await counts.read_data_type() == ua.NodeId(ua.ObjectIds.Int16)
            grid = client.get_node(f"ns={ns};s=Grid.@Value")
            assert await grid.read_value_rank() == 2 and await grid.read_array_dimensions() == [2, 3]
            assert await grid.read_value() == [[0.0] * 3] * 2
            # the per-element variables stay
            assert await client.get_node(f"ns={ns};s=Counts[3]").read_value() == 3
            # an array of structs has no array variable (its elements are objects)
            with pytest.raises(ua.UaStatusCodeError):
                await client.get_node(f"ns={ns};s=Path.@Value").read_value()
    run_async(body())


def test_index_range_reads(arrays):
    async def body():
        async with Client(arrays.url) as client:
            ns = await client.get_namespace_index(arrays.ns_uri)
            counts = client.get_node(f"ns={ns};s=Counts.@Value")
            results = await read_items(client, counts, "2", "1:3", "3:9", "5", "7:8", "2:1", "x", "1,1", "-1")
            assert [r.Value.Value for r in results[:3]] == [[3], [2, 3, 4], [4, 5]]   # past the end: the part there
            assert [r.StatusCode.value for r in results[3:]] == [
                ua.StatusCodes.BadIndexRangeNoData, ua.StatusCodes.BadIndexRangeNoData,   # starts past the end
                ua.StatusCodes.BadIndexRangeInvalid, ua.StatusCodes.BadIndexRangeInvalid,  # 2:1, x
                ua.StatusCodes.BadIndexRangeNoData,                                        # 2 dims of a 1-dim array
                ua.StatusCodes.BadIndexRangeInvalid]
            grid = client.get_node(f"ns={ns};s=Grid.@Value")
            [cell] = await read_items(client, grid, "1,0:1")
            assert cell.StatusCode.is_good() and cell.Value.Dimensions == [1, 2]
            names = client.get_node(f"ns={ns};s=Names.@Value")
            [chars] = await read_items(client, names, "1:2,0")       # a string array: characters too
            assert chars.Value.Value == ["b", "c"]
    run_async(body())


def test_index_range_writes_checked_per_element(arrays):
    async def body():
        async with Client(arrays.url) as client:
            ns = await client.get_namespace_index(arrays.ns_uri)
            counts = client.get_node(f"ns={ns};s=Counts.@Value")
            assert (await write_range(client, counts, "1:2", ua.Variant([20, 30], ua.VariantType.Int16))).is_good()
            assert (arrays.vm["Counts[2]"], arrays.vm["Counts[3]"]) == (20, 30)
            assert await counts.read_value() == [1, 20, 30, 4, 5]
            assert (await write_range(client, counts, "4", ua.Variant([50], ua.VariantType.Int16))).is_good()
            assert arrays.vm["Counts[5]"] == 50
            bad = {
                "1:2 with 3 values": ("1:2", ua.Variant([1, 2, 3], ua.VariantType.Int16),
                                      ua.StatusCodes.BadIndexRangeDataMismatch),
                "past the end": ("4:5", ua.Variant([1, 2], ua.VariantType.Int16), ua.StatusCodes.BadIndexRangeNoData),
                "no range": ("3:1", ua.Variant([1], ua.VariantType.Int16), ua.StatusCodes.BadIndexRangeInvalid),
                "over the limit": ("0:1", ua.Variant([5, 101], ua.VariantType.Int16), ua.StatusCodes.BadOutOfRange),
                "wrong type": ("0", ua.Variant(["a"], ua.VariantType.String), ua.StatusCodes.BadTypeMismatch),
            }
            for what, (index_range, variant, status) in bad.items():
                assert (await write_range(client, counts, index_range, variant)).value == status, what
            assert await counts.read_value() == [1, 20, 30, 4, 50]   # a refused write changes nothing
            await counts.write_value(ua.Variant([9, 8, 7, 6, 5], ua.VariantType.Int16))
            assert [arrays.vm[f"Counts[{i}]"] for i in range(1, 6)] == [9, 8, 7, 6, 5]
            with pytest.raises(ua.UaStatusCodeError):                  # the whole array: its exact size
                await counts.write_value(ua.Variant([1, 2], ua.VariantType.Int16))
            grid = client.get_node(f"ns={ns};s=Grid.@Value")
            assert (await write_range(client, grid, "1,1:2", ua.Variant([[1.5, 2.5]], ua.VariantType.Float,
                                                                          Dimensions=[1, 2]))).is_good()
            assert (arrays.vm["Grid[2,1]"], arrays.vm["Grid[2,2]"]) == (1.5, 2.5)
    run_async(body())


def test_array_variable_is_monitored(arrays):
    async def body():
        async with Client(arrays.url) as client:
            ns = await client.get_namespace_index(arrays.ns_uri)
            counts = client.get_node(f"ns={ns};s=Counts.@Value")
            seen: list = []

            class Changes:
                def datachange_notification(self, node, value, data):
                    seen.append(value)
            sub = await client.create_subscription(10, Changes())
            await sub.subscribe_data_change(counts)
            await client.get_node(f"ns={ns};s=Counts[4]").write_value(ua.Variant(44, ua.VariantType.Int16))
            await client.get_node(f"ns={ns};s=@Runtime").call_method(f"{ns}:Scan", ua.Variant(3, ua.VariantType.UInt32))
            for _ in range(200):
                if seen and seen[-1] == [1, 2, 3, 44, 5]:
                    break
                await asyncio.sleep(0.02)
            assert seen[-1] == [1, 2, 3, 44, 5]
    run_async(body())
