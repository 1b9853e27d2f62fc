"""The OPC UA server on the thesis project, driven by asyncua's client over loopback."""

from __future__ import annotations

import asyncio

import pytest
from asyncua import Client, ua
from asyncua.ua import uaerrors
from opcua_helpers import Running, run_async, wire_demo

import stvm
from stvm.lockstep import start_lockstep


async def ns_index(client: Client, running: Running) -> int:
    return await client.get_namespace_index(running.ns_uri)


def node(client: Client, ns: int, path: str):
    return client.get_node(f"ns={ns};s={path}")


async def scan(client: Client, ns: int, count: int) -> int:
    runtime = node(client, ns, "@Runtime")
    return await runtime.call_method(f"{ns}:Scan", ua.Variant(count, ua.VariantType.UInt32))


def test_browse_tree_and_nodeids_are_stvm_paths(running):
    async def body():
        async with Client(running.url) as client:
            ns = await ns_index(client, running)
            top = {(await n.read_browse_name()).Name: n for n in await client.nodes.objects.get_children()}
            assert {"Globals", "PnP_Example_Instance", "Program_Example_Instance", "Runtime"} <= set(top)
            assert top["Globals"].nodeid == ua.NodeId("@Globals", ns)
            cobot = await top["Globals"].get_child(f"{ns}:Cobot")
            assert cobot.nodeid == ua.NodeId("Cobot", ns)
            assert await cobot.read_node_class() == ua.NodeClass.Object
            members = {(await c.read_browse_name()).Name for c in await cobot.get_children()}
            assert "Connected" in members
            x = await top["Globals"].get_child([f"{ns}:PnP_MoveParameters", f"{ns}:[2]",
                                                f"{ns}:TargetPosition", f"{ns}:X"])
            assert x.nodeid == ua.NodeId("PnP_MoveParameters[2].TargetPosition.X", ns)
            assert await x.read_data_type() == ua.NodeId(ua.ObjectIds.Float)
            step = await top["PnP_Example_Instance"].get_child(f"{ns}:Prg_Step")
            assert step.nodeid == ua.NodeId("PnP_Example_Instance.Prg_Step", ns)
            assert await step.read_data_type() == ua.NodeId(ua.ObjectIds.Int16)
            # FB internals are not published by default; their instances do not appear either
            names = {(await c.read_browse_name()).Name for c in await top["PnP_Example_Instance"].get_children()}
            assert "Prg_Step" in names and "CBT_MoveAbsolute_Instance" not in names and "Timer_1" not in names
            assert "STRING[50]" in (await node(client, ns, "Connect_ErrorDescrip").read_description()).Text
    run_async(body())


def test_read_and_write_scalars_members_and_elements(running):
    async def body():
        async with Client(running.url) as client:
            ns = await ns_index(client, running)
            port = node(client, ns, "Connect_Dest_PortIP")
            speed = node(client, ns, "PnP_MoveParameters[2].Speed")
            x = node(client, ns, "PnP_MoveParameters[2].TargetPosition.X")
            address = node(client, ns, "Connect_AddressIP")
            assert await speed.read_value() == 20            # the demo scenario's segment 3
            assert await x.read_value() == 400.0
            assert await address.read_value() == "127.0.0.1"
            await port.write_value(ua.Variant(4242, ua.VariantType.Int16))
            await x.write_value(ua.Variant(412.5, ua.VariantType.Float))
            await speed.write_value(5)                        # a Python int arrives as Int64: it fits
            await address.write_value(ua.Variant("10.0.0.7", ua.VariantType.String))
            assert [await n.read_value() for n in (port, x, speed, address)] == [4242, 412.5, 5, "10.0.0.7"]
            await scan(client, ns, 1)
        vm = running.vm   # after the client is done and the VM is held between scans
        assert vm["Connect_Dest_PortIP"] == 4242 and vm["PnP_MoveParameters[2].TargetPosition.X"] == 412.5
        assert vm["PnP_MoveParameters[2].Speed"] == 5 and vm["Connect_AddressIP"] == b"10.0.0.7"
    run_async(body())


def test_enum_has_its_datatype_with_enumstrings(running):
    async def body():
        async with Client(running.url) as client:
            ns = await ns_index(client, running)
            command = node(client, ns, "PnP_MoveParameters[0].MovementCommand")
            assert await command.read_value() == 1                       # PTP
            datatype = client.get_node(await command.read_data_type())
            assert (await datatype.read_browse_name()).Name == "eCBT_MovCmd_Movement"
            strings = await (await datatype.get_child("0:EnumStrings")).read_value()
            assert [s.Text for s in strings] == ["Line", "PTP"]
            await command.write_value(ua.Variant(0, ua.VariantType.Int32))
            assert await command.read_value() == 0
            with pytest.raises(uaerrors.BadOutOfRange):
                await command.write_value(ua.Variant(7, ua.VariantType.Int32))
    run_async(body())


def test_bad_writes_get_their_status_and_change_nothing(running):
    async def body():
        async with Client(running.url) as client:
            ns = await ns_index(client, running)
            await scan(client, ns, 3)
            cases = [
                ("Connect_Dest_PortIP", ua.Variant("5890", ua.VariantType.String), uaerrors.BadTypeMismatch),
                ("Connect_Dest_PortIP", ua.Variant(70000, ua.VariantType.Int32), uaerrors.BadOutOfRange),
                ("Connect_Execute", ua.Variant(1, ua.VariantType.Int32), uaerrors.BadTypeMismatch),
                ("Connect_AddressIP", ua.Variant("x" * 50, ua.VariantType.String), uaerrors.BadOutOfRange),
                ("PnP_MoveParameters[1].TargetPosition.Z", ua.Variant(1e39, ua.VariantType.Double),
                 uaerrors.BadOutOfRange),
                ("PnP_Example_Instance.Prg_Step", ua.Variant(5, ua.VariantType.Int16), uaerrors.BadNotWritable),
                ("Connect_Dest_PortIP", ua.Variant([1, 2], ua.VariantType.Int16), uaerrors.BadTypeMismatch),
            ]
            before = {path: await node(client, ns, path).read_value() for path, _, _ in cases}
            for path, variant, error in cases:
                with pytest.raises(error):
                    await node(client, ns, path).write_value(variant)
            with pytest.raises(uaerrors.BadNotWritable):   # only the Value attribute is writable
                await node(client, ns, "Connect_Execute").write_attribute(
                    ua.AttributeIds.DisplayName, ua.DataValue(ua.Variant(ua.LocalizedText("x"))))
            # one request: the good item is applied, the bad one refused (per-item results)
            params = ua.WriteParameters()
            for path, variant in (("Connect_Time_Out", ua.Variant(77, ua.VariantType.UInt16)),
                                  ("Connect_Time_Out", ua.Variant(-1, ua.VariantType.Int32))):
                item = ua.WriteValue(NodeId=ua.NodeId(path, ns), AttributeId=ua.AttributeIds.Value,
                                     Value=ua.DataValue(variant))
                params.NodesToWrite.append(item)
            params.NodesToWrite.append(ua.WriteValue(NodeId=ua.NodeId("Connect_Time_Out", ns),
                                                     AttributeId=ua.AttributeIds.Value, IndexRange="0",
                                                     Value=ua.DataValue(ua.Variant(5, ua.VariantType.UInt16))))
            results = await client.uaclient.write(params)
            assert [r.value for r in results] == [ua.StatusCodes.Good, ua.StatusCodes.BadOutOfRange,
                                                  ua.StatusCodes.BadWriteNotSupported]
            await scan(client, ns, 1)
            after = {path: await node(client, ns, path).read_value() for path, _, _ in cases}
            assert after == before and await node(client, ns, "Connect_Time_Out").read_value() == 77
    run_async(body())


def test_scan_method_steps_deterministically(thesis_project):
    # the reference: the same wiring without a server, run by hand
    reference, _ = start_lockstep(thesis_project, "1ms")
    wire_demo(reference)
    paths = ["PnP_Example_Instance.Prg_Step", "Cobot.Connected", "Connect_Busy", "PnP_MoveBusy",
             "PnP_Move_CmdID_Ack", "Connect_LastConnTime"]
    expected = {}
    for done in (40, 400, 1200):
        reference.run(cycles=done - reference.scan_count)
        expected[done] = [reference.get(p) for p in paths]
    reference.close()
    run = Running(thesis_project)
    try:
        async def body():
            async with Client(run.url) as client:
                ns = await ns_index(client, run)
                got = {}
                for done in (40, 400, 1200):
                    assert await scan(client, ns, done - await node(client, ns, "@Runtime.ScanCount").read_value()) \
                        == done
                    values = await client.read_values([node(client, ns, p) for p in paths])
                    got[done] = values
                    stamp = (await node(client, ns, "PnP_Example_Instance.Prg_Step").read_data_value()).ServerTimestamp
                    assert stamp.replace(tzinfo=None).isoformat().startswith("1970-01-01T00:00:0")  # VM time
                return got
        got = run_async(body())
    finally:
        run.close()
    from stvm.opcua.datatypes import datetime_of
    for done, values in expected.items():
        converted = [datetime_of(v).replace(tzinfo=None) if p == "Connect_LastConnTime" else v
                     for p, v in zip(paths, values)]
        assert [v.replace(tzinfo=None) if hasattr(v, "tzinfo") else v for v in got[done]] == converted
    assert expected[1200][1] is True          # the connect ran against the emulated robot meanwhile


def test_subscription_sees_cobot_connected_change_during_connect(running):
    async def body():
        async with Client(running.url) as client:
            ns = await ns_index(client, running)
            seen: list[tuple[bool, object]] = []
            changed = asyncio.Event()

            class Handler:
                def datachange_notification(self, monitored, value, data):
                    seen.append((value, data.monitored_item.Value.SourceTimestamp))
                    if value is True:
                        changed.set()
            subscription = await client.create_subscription(20, Handler())
            await subscription.subscribe_data_change(node(client, ns, "Cobot.Connected"))
            await asyncio.sleep(0.1)
            assert running.server.monitored_paths == {"Cobot.Connected"}
            await node(client, ns, "@Runtime").call_method(f"{ns}:Resume")
            await asyncio.wait_for(changed.wait(), 20)
            assert seen[0][0] is False and seen[-1][0] is True
            assert seen[-1][1] > seen[0][1]    # source time stamps are VM time of the sampled scans
            await subscription.delete()
            await asyncio.sleep(0.1)
            assert running.server.monitored_paths == set()
    run_async(body())


def test_fifty_clients_subscribed_at_once(running):
    async def one_client(index: int, resumed: asyncio.Event, results: list):
        client = Client(running.url, timeout=30)
        await client.connect()
        try:
            ns = await ns_index(client, running)
            values = []
            done = asyncio.Event()

            class Handler:
                def datachange_notification(self, monitored, value, data):
                    values.append(value)
                    if value is True:
                        done.set()
            subscription = await client.create_subscription(50, Handler())
            await subscription.subscribe_data_change([node(client, ns, "Cobot.Connected"),
                                                      node(client, ns, "PnP_Example_Instance.Prg_Step")])
            results.append(index)
            await resumed.wait()
            await asyncio.wait_for(done.wait(), 30)
            return True in values
        finally:
            await client.disconnect()

    async def body():
        resumed = asyncio.Event()
        subscribed: list[int] = []
        tasks = [asyncio.ensure_future(one_client(i, resumed, subscribed)) for i in range(50)]
        while len(subscribed) < 50:
            await asyncio.sleep(0.05)
            if any(t.done() for t in tasks):
                break
        assert len(subscribed) == 50
        assert running.server.monitored_paths == {"Cobot.Connected", "PnP_Example_Instance.Prg_Step"}
        async with Client(running.url) as control:
            ns = await ns_index(control, running)
            await node(control, ns, "@Runtime").call_method(f"{ns}:Resume")
        resumed.set()
        assert all(await asyncio.gather(*tasks))
    run_async(body(), timeout=120)
    assert running.vm.scan_count > 0


def test_client_vanishing_mid_subscription(running):
    async def body():
        gone = Client(running.url)
        await gone.connect()
        ns = await ns_index(gone, running)

        class Quiet:
            def datachange_notification(self, *args):
                pass
        # A session and its subscriptions outlive a lost connection (the client may reconnect and
        # transfer them): its monitored items go when the subscription's lifetime (here 30
        # publishing intervals of 10 ms without a Publish request) or the session timeout runs out.
        params = ua.CreateSubscriptionParameters(RequestedPublishingInterval=10, RequestedLifetimeCount=30,
                                                 RequestedMaxKeepAliveCount=10, PublishingEnabled=True)
        subscription = await gone.create_subscription(params, Quiet())
        await subscription.subscribe_data_change([node(gone, ns, "Cobot.Connected"), node(gone, ns, "Connect_Busy")])
        async with Client(running.url) as other:
            await node(other, ns, "@Runtime").call_method(f"{ns}:Resume")
            await asyncio.sleep(0.2)
            assert running.server.monitored_paths == {"Cobot.Connected", "Connect_Busy"}
            gone.uaclient.protocol.transport.abort()     # the TCP connection drops, no CloseSession
            for _ in range(200):
                if not running.server.monitored_paths:
                    break
                await asyncio.sleep(0.05)
            assert running.server.monitored_paths == set()
            before = await node(other, ns, "@Runtime.ScanCount").read_value()
            await asyncio.sleep(0.2)
            assert await node(other, ns, "@Runtime.ScanCount").read_value() > before   # the VM runs on
            assert await node(other, ns, "Cobot.Connected").read_value() in (True, False)
        try:
            await gone.disconnect()
        except Exception:   # noqa: BLE001 - its connection is gone
            pass
    run_async(body())


def test_pause_resume_and_bad_scan_counts(running):
    async def body():
        async with Client(running.url) as client:
            ns = await ns_index(client, running)
            runtime = node(client, ns, "@Runtime")
            paused, count = node(client, ns, "@Runtime.Paused"), node(client, ns, "@Runtime.ScanCount")
            assert await paused.read_value() is True                  # start = "paused"
            await runtime.call_method(f"{ns}:Resume")
            await asyncio.sleep(0.3)
            await runtime.call_method(f"{ns}:Pause")
            assert await paused.read_value() is True
            first = await count.read_value()
            await asyncio.sleep(0.2)
            assert first > 0 and await count.read_value() == first   # held between two scans
            assert await scan(client, ns, 2) == first + 2
            with pytest.raises(uaerrors.BadOutOfRange):
                await scan(client, ns, 0)
            with pytest.raises(uaerrors.BadTypeMismatch):
                await runtime.call_method(f"{ns}:Scan", ua.Variant("ten", ua.VariantType.String))
            assert await count.read_value() == first + 2
    run_async(body())


def test_sampling_interval_slower_than_a_scan(tmp_path):
    source = tmp_path / "count.st"
    source.write_text("PROGRAM Main VAR n : DINT; END_VAR n := n + 1; END_PROGRAM\n")
    run = Running(stvm.load([str(source)]), demo=False, files=[str(source)])
    try:
        async def body():
            async with Client(run.url) as client:
                ns = await ns_index(client, run)
                fast, slow = [], []

                class Into:
                    def __init__(self, sink):
                        self.sink = sink

                    def datachange_notification(self, monitored, value, data):
                        self.sink.append(value)
                every_scan = await client.create_subscription(10, Into(fast))
                every_10ms = await client.create_subscription(10, Into(slow))
                counter = node(client, ns, "Main.n")
                # a queue per monitored item: a publishing cycle the (loaded) machine delays must
                # not let one sample overwrite the last (the default queue holds one)
                await every_scan.subscribe_data_change(counter, sampling_interval=0, queuesize=64)
                await every_10ms.subscribe_data_change(counter, sampling_interval=10)
                for _ in range(6):
                    await scan(client, ns, 5)     # VM time 5 ms per call
                    await asyncio.sleep(0.05)     # one publishing interval at least
                for _ in range(100):              # the last publishing cycle, however late
                    if 30 in fast and 21 in slow:
                        break
                    await asyncio.sleep(0.05)
                return fast, slow
        fast, slow = run_async(body())
    finally:
        run.close()
    assert fast[-1] == 30 and {5, 10, 15, 20, 25, 30} <= set(fast)   # sampled at the end of every scan
    assert set(slow) - {0} <= {1, 11, 21} and 21 in slow                # scans 0, 10, 20: every 10 ms of VM time
