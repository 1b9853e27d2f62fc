"""OPC UA Alarms & Conditions on the thesis project: a real FB error (a move with no robot
connected) seen as an AlarmConditionType event by asyncua's client, acknowledged over OPC UA and
in the shared alarm list, and re-sent by ConditionRefresh to a client that subscribes late."""

from __future__ import annotations

import asyncio

import pytest
from asyncua import Client, ua
from opcua_helpers import Running, run_async

from stvm.frontend.alarms import AlarmList

SOURCE = "Program_Example_Instance.CBT_MoveAbsolute_Instance"
ACK = ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge)
REFRESH = ua.NodeId(ua.ObjectIds.ConditionType_ConditionRefresh)


class Events:
    def __init__(self) -> None:
        self.received: list = []

    def event_notification(self, event) -> None:
        self.received.append(event)

    async def wait_for(self, predicate, timeout: float = 10.0):
        deadline = asyncio.get_running_loop().time() + timeout
        while asyncio.get_running_loop().time() < deadline:
            found = [e for e in self.received if predicate(e)]
            if found:
                return found[-1]
            await asyncio.sleep(0.02)
        raise AssertionError(f"no such event among {[(e.EventType, e.SourceName) for e in self.received]}")


def of_source(event) -> bool:
    return event.EventType == ua.NodeId(ua.ObjectIds.AlarmConditionType) and event.SourceName == SOURCE


async def step(client: Client, ns: int, scans: int) -> None:
    await client.get_node(f"ns={ns};s=@Runtime").call_method(f"{ns}:Scan", ua.Variant(scans, ua.VariantType.UInt32))


async def provoke(client: Client, ns: int) -> None:
    """MoveAbs_Execute with no robot connected: CBT_MoveAbsolute sets Error, 16#0099."""
    await client.get_node(f"ns={ns};s=MoveAbs_Execute").write_value(True)
    await step(client, ns, 5)


@pytest.fixture
def idle(thesis_project):
    run = Running(thesis_project, demo=False)   # no robot: a move fails
    yield run
    run.close()


def test_fb_error_is_an_alarm_event_on_the_server_and_the_fb_object_and_ack_works(idle):
    async def body():
        async with Client(idle.url) as client:
            ns = await client.get_namespace_index(idle.ns_uri)
            source_node = client.get_node(f"ns={ns};s={SOURCE}")
            at_server, at_source = Events(), Events()
            sub = await client.create_subscription(10, at_server)
            await sub.subscribe_events(client.nodes.server, ua.ObjectIds.AlarmConditionType)
            sub2 = await client.create_subscription(10, at_source)
            await sub2.subscribe_events(source_node, ua.ObjectIds.AlarmConditionType)
            await provoke(client, ns)
            raised = await at_server.wait_for(lambda e: of_source(e) and getattr(e, "ActiveState/Id"))
            same = await at_source.wait_for(lambda e: of_source(e) and getattr(e, "ActiveState/Id"))
            assert same.EventId == raised.EventId
            assert raised.Message.Text == "Robot not connected (ErrorID 16#0099)"
            assert raised.Severity == 700 and raised.ConditionName == "Error" and raised.Retain is True
            assert raised.SourceNode == source_node.nodeid
            assert getattr(raised, "AckedState/Id") is False and raised.ActiveState.Text == "Active"
            assert raised.Time.year == 1970        # the virtual clock: VM time, not the host's
            assert raised.NodeId == ua.NodeId(f"{SOURCE}.@Error", ns)    # the ConditionId
            assert raised.InputNode == ua.NodeId("MoveAbs_Error", ns) or raised.InputNode == ua.NodeId()
            # the same alarm is the HMI's
            [alarm] = [a for a in idle.server.alarm_list.current() if a.source == SOURCE]
            assert (alarm.active, alarm.acknowledged, alarm.code) == (True, False, 0x99)

            condition = client.get_node(raised.NodeId)
            await condition.call_method(ACK, ua.Variant(raised.EventId, ua.VariantType.ByteString),
                                        ua.LocalizedText("seen"))
            acked = await at_server.wait_for(lambda e: of_source(e) and getattr(e, "AckedState/Id"))
            assert getattr(acked, "ActiveState/Id") is True and acked.Retain is True   # still active
            assert acked.Comment.Text == "seen"
            assert [a.acknowledged for a in idle.server.alarm_list.current() if a.source == SOURCE] == [True]
            # twice: already acknowledged; an EventId never sent: unknown
            with pytest.raises(ua.UaStatusCodeError) as twice:
                await condition.call_method(ACK, ua.Variant(acked.EventId, ua.VariantType.ByteString),
                                            ua.LocalizedText("again"))
            assert twice.value.code == ua.StatusCodes.BadConditionBranchAlreadyAcked
            with pytest.raises(ua.UaStatusCodeError) as unknown:
                await condition.call_method(ACK, ua.Variant(b"no such event", ua.VariantType.ByteString),
                                            ua.LocalizedText(""))
            assert unknown.value.code == ua.StatusCodes.BadEventIdUnknown

            # the error returns: an inactive, acknowledged condition is no longer retained
            await client.get_node(f"ns={ns};s=MoveAbs_Execute").write_value(False)
            await step(client, ns, 5)
            cleared = await at_server.wait_for(lambda e: of_source(e) and not getattr(e, "ActiveState/Id"))
            assert cleared.Retain is False and cleared.ActiveState.Text == "Inactive"
            assert not [a for a in idle.server.alarm_list.current() if a.source == SOURCE]
    run_async(body())


def test_acknowledged_in_the_shared_list_is_an_event_too(idle):
    # the HMI acknowledges through the same list (AlarmList.attach hands every front end one list)
    shared = AlarmList.attach(idle.server.bridge)
    try:
        assert shared is idle.server.alarm_list

        async def body():
            async with Client(idle.url) as client:
                ns = await client.get_namespace_index(idle.ns_uri)
                events = Events()
                sub = await client.create_subscription(10, events)
                await sub.subscribe_events(client.nodes.server, ua.ObjectIds.AlarmConditionType)
                await provoke(client, ns)
                await events.wait_for(lambda e: of_source(e) and getattr(e, "ActiveState/Id"))
                [alarm] = [a for a in shared.current() if a.source == SOURCE]
                shared.acknowledge(alarm.id)        # what the HMI's ack button does
                acked = await events.wait_for(lambda e: of_source(e) and getattr(e, "AckedState/Id"))
                assert acked.AckedState.Text == "Acknowledged"
        run_async(body())
    finally:
        shared.close()


def test_condition_refresh_sends_retained_alarms_to_a_late_subscriber(idle):
    async def body():
        async with Client(idle.url) as client:
            ns = await client.get_namespace_index(idle.ns_uri)
            await provoke(client, ns)
            await asyncio.sleep(0.2)
            late = Events()
            sub = await client.create_subscription(10, late)
            await sub.subscribe_events(client.nodes.server, ua.ObjectIds.AlarmConditionType)
            await client.nodes.server.call_method(REFRESH, ua.Variant(sub.subscription_id, ua.VariantType.UInt32))
            end = await late.wait_for(lambda e: e.EventType == ua.NodeId(ua.ObjectIds.RefreshEndEventType))
            kinds = [e.EventType.Identifier for e in late.received]
            start = kinds.index(ua.ObjectIds.RefreshStartEventType)
            retained = [e for e in late.received[start:] if of_source(e)]
            assert retained and retained[0].Retain is True and getattr(retained[0], "ActiveState/Id") is True
            assert kinds.index(ua.ObjectIds.RefreshEndEventType) > kinds.index(ua.ObjectIds.AlarmConditionType) > start
            assert end.EventId != late.received[start].EventId
            with pytest.raises(ua.UaStatusCodeError) as bad:
                await client.nodes.server.call_method(REFRESH, ua.Variant(987654, ua.VariantType.UInt32))
            assert bad.value.code == ua.StatusCodes.BadSubscriptionIdInvalid
    run_async(body())


def test_alarm_objects_and_conditions_are_browsable(idle):
    async def body():
        async with Client(idle.url) as client:
            ns = await client.get_namespace_index(idle.ns_uri)
            folder = await client.nodes.objects.get_child(f"{ns}:Alarms")
            names = {(await n.read_browse_name()).Name for n in await folder.get_children()}
            assert SOURCE in names
            source = client.get_node(f"ns={ns};s={SOURCE}")
            [condition] = await source.get_referenced_nodes(refs=ua.ObjectIds.HasCondition)
            assert condition.nodeid == ua.NodeId(f"{SOURCE}.@Error", ns)
            assert (await condition.read_type_definition()) == ua.NodeId(ua.ObjectIds.AlarmConditionType)
            notifier = await source.read_event_notifier()
            assert ua.EventNotifier.SubscribeToEvents in notifier
    run_async(body())


def test_alarms_switch_off(thesis_project):
    run = Running(thesis_project, opcua={"alarms": False}, demo=False)
    try:
        assert run.server.alarm_list is None and run.server.conditions is None

        async def body():
            async with Client(run.url) as client:
                ns = await client.get_namespace_index(run.ns_uri)
                with pytest.raises(ua.UaStatusCodeError):
                    await client.nodes.objects.get_child(f"{ns}:Alarms")
        run_async(body())
    finally:
        run.close()
