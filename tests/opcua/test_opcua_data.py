"""OPC UA data as clients expect it (issue 32 items 8–10): time stamps from the first scan,
Runtime.ScanCount at the sampling interval, IndexRange, HistoryRead and Runtime write statuses."""

from __future__ import annotations

import asyncio
import time

from asyncua import Client, ua

from opcua_helpers import THESIS, run_async
from stvm.opcua import load_config
from stvm.opcua.datatypes import ns_of
from stvm.opcua.server import OpcUaServer


def test_realtime_stamps_start_at_the_first_scan_not_at_server_creation(thesis_project):
    vm = thesis_project.start(scan="10ms", realtime=True)
    try:
        server = OpcUaServer(vm, load_config(thesis_project.manifest, thesis_project.root, THESIS,
                                             "opc.tcp://127.0.0.1:0"))
        time.sleep(0.3)   # a slow start-up between creating the server and the first scan
        before = time.time_ns()
        vm.run(cycles=1)
        after = time.time_ns()
        stamp = ns_of(server._timestamp(0))     # the stamp a value of scan 0 gets
        assert before - 1_000_000 <= stamp <= after
    finally:
        vm.close()


def test_index_range_history_read_and_runtime_write_statuses(running):
    async def body():
        async with Client(running.url) as client:
            ns = await client.get_namespace_index(running.ns_uri)
            speed = ua.NodeId("PnP_MoveParameters[2].Speed", ns)

            async def read(index_range):
                params = ua.ReadParameters(NodesToRead=[ua.ReadValueId(NodeId=speed, AttributeId=ua.AttributeIds.Value,
                                                                       IndexRange=index_range)])
                return (await client.uaclient.read(params))[0].StatusCode.value
            assert await read("0") == ua.StatusCodes.BadIndexRangeNoData       # a scalar has no elements
            assert await read("2:1") == ua.StatusCodes.BadIndexRangeInvalid     # not a NumericRange
            assert await read("x") == ua.StatusCodes.BadIndexRangeInvalid
            assert await read(None) == ua.StatusCodes.Good

            write = ua.WriteValue(NodeId=speed, AttributeId=ua.AttributeIds.Value, IndexRange="1",
                                  Value=ua.DataValue(ua.Variant(5.0, ua.VariantType.Float)))
            scan_count = ua.WriteValue(NodeId=ua.NodeId("@Runtime.ScanCount", ns), AttributeId=ua.AttributeIds.Value,
                                       Value=ua.DataValue(ua.Variant(5, ua.VariantType.UInt64)))
            statuses = await client.uaclient.write(ua.WriteParameters(NodesToWrite=[write, scan_count]))
            assert [s.value for s in statuses] == [ua.StatusCodes.BadWriteNotSupported, ua.StatusCodes.BadNotWritable]

            history = ua.HistoryReadParameters(
                HistoryReadDetails=ua.ReadRawModifiedDetails(IsReadModified=False, NumValuesPerNode=10,
                                                            StartTime=ua.get_win_epoch(), EndTime=ua.get_win_epoch()),
                TimestampsToReturn=ua.TimestampsToReturn.Both,
                NodesToRead=[ua.HistoryReadValueId(NodeId=speed), ua.HistoryReadValueId(NodeId=ua.NodeId("nope", ns))])
            results = await client.uaclient.history_read(history)
            assert [r.StatusCode.value for r in results] == [ua.StatusCodes.BadHistoryOperationUnsupported,
                                                              ua.StatusCodes.BadNodeIdUnknown]
            # and the nodes say so: not historizing, no HistoryRead access
            assert (await client.get_node(speed).read_attribute(ua.AttributeIds.Historizing)).Value.Value is False
            access = (await client.get_node(speed).read_attribute(ua.AttributeIds.AccessLevel)).Value.Value
            assert not access & ua.AccessLevel.HistoryRead.mask
    run_async(body())


def test_scan_count_notifies_at_the_sampling_interval(running):
    seen: list[int] = []

    class Into:
        def datachange_notification(self, node, value, data):
            seen.append(value)

    async def body():
        async with Client(running.url) as client:
            ns = await client.get_namespace_index(running.ns_uri)
            sub = await client.create_subscription(10, Into())
            await sub.subscribe_data_change(client.get_node(ua.NodeId("@Runtime.ScanCount", ns)),
                                            sampling_interval=0, queuesize=100)
            runtime = client.get_node(ua.NodeId("@Runtime", ns))
            for _ in range(5):
                await runtime.call_method(f"{ns}:Scan", ua.Variant(1, ua.VariantType.UInt32))
                await asyncio.sleep(0.1)     # a publishing interval passes: each step is notified
            await asyncio.sleep(0.3)
    run_async(body())
    # every scan is notified (before: only every 1,000 scans, whatever the interval asked)
    assert [1, 2, 3, 4, 5] == [v for v in seen if v >= 1][:5]
