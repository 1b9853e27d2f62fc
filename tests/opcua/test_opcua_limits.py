"""Issue 32 item 11: OPC UA writes enforce the operator limits table the HMI enforces
(stvm/frontend/limits.py), limited variables carry EURange / EngineeringUnits, outputs and status
are read-only (AccessLevel and BadNotWritable) unless the table's `@outputs` switch opens them."""

from __future__ import annotations

import math

import pytest
from asyncua import Client, ua
from asyncua.common.utils import ServiceError  # noqa: F401 (asyncua raises its Bad* subclasses)

from opcua_helpers import Running, run_async
from stvm.opcua.engineering import unit_id


async def _write_status(client, nodeid, variant) -> int:
    params = ua.WriteParameters(NodesToWrite=[ua.WriteValue(NodeId=nodeid, AttributeId=ua.AttributeIds.Value,
                                                            Value=ua.DataValue(variant))])
    return (await client.uaclient.write(params))[0].value


def test_writes_outside_the_limits_table_are_bad_out_of_range(running):
    async def body():
        async with Client(running.url) as client:
            ns = await client.get_namespace_index(running.ns_uri)
            speed = ua.NodeId("MoveAbs_Param.Speed", ns)
            x = ua.NodeId("MoveAbs_Param.TargetPosition.X", ns)
            timeout = ua.NodeId("Connect_Time_Out", ns)
            out_of_range = ua.StatusCodes.BadOutOfRange
            assert await _write_status(client, speed, ua.Variant(9000, ua.VariantType.UInt16)) == out_of_range
            assert await _write_status(client, x, ua.Variant(math.nan, ua.VariantType.Float)) == out_of_range
            assert await _write_status(client, x, ua.Variant(math.inf, ua.VariantType.Float)) == out_of_range
            assert await _write_status(client, x, ua.Variant(-math.inf, ua.VariantType.Float)) == out_of_range
            assert await _write_status(client, x, ua.Variant(99999999.0, ua.VariantType.Float)) == out_of_range
            timeout_type = ua.VariantType((await client.get_node(timeout).read_data_type_as_variant_type()).value)
            assert await _write_status(client, timeout, ua.Variant(500, timeout_type)) == out_of_range
            # inside the limits: Good, and the value arrives
            assert await _write_status(client, speed, ua.Variant(77, ua.VariantType.UInt16)) == ua.StatusCodes.Good
            assert await _write_status(client, x, ua.Variant(-350.5, ua.VariantType.Float)) == ua.StatusCodes.Good
            assert await client.get_node(speed).read_value() == 77
            assert await client.get_node(x).read_value() == pytest.approx(-350.5)
    run_async(body())


def test_limited_variables_are_analog_items_with_eurange_and_engineering_units(running):
    async def body():
        async with Client(running.url) as client:
            ns = await client.get_namespace_index(running.ns_uri)
            x = client.get_node(ua.NodeId("MoveAbs_Param.TargetPosition.X", ns))
            assert await x.read_type_definition() == ua.NodeId(ua.ObjectIds.AnalogItemType)
            eu_range = await x.get_child("0:EURange")
            assert await eu_range.read_value() == ua.Range(Low=-1000.0, High=1000.0)
            units = await (await x.get_child("0:EngineeringUnits")).read_value()
            assert (units.DisplayName.Text, units.UnitId) == ("mm", unit_id("MMT"))
            assert units.NamespaceUri == "http://www.opcfoundation.org/UA/units/un/cefact"
            # the property is read-only
            assert await _write_status(client, eu_range.nodeid, ua.Variant(ua.Range(Low=0.0, High=1.0))) \
                == ua.StatusCodes.BadNotWritable
            # a unit without a UNECE code: UnitId -1, the text as its name
            speed_units = await (await client.get_node(ua.NodeId("MoveAbs_Param.Speed", ns))
                                 .get_child("0:EngineeringUnits")).read_value()
            assert (speed_units.DisplayName.Text, speed_units.UnitId) == ("% | mm/s", -1)
            # a variable with only its type's range has neither property
            step = client.get_node(ua.NodeId("PnP_Example_Instance.Prg_Step", ns))
            assert await step.get_properties() == []
            assert await step.read_type_definition() == ua.NodeId(ua.ObjectIds.BaseDataVariableType)
    run_async(body())


STATUS = ("Cobot.Connected", "Cobot.Socket.Handle", "Connect_Busy", "MoveRel_Done", "MoveAbs_Error",
          "PnP_MoveErrorDescrip")


def test_outputs_and_status_are_read_only_by_default(running):
    async def body():
        async with Client(running.url) as client:
            ns = await client.get_namespace_index(running.ns_uri)
            read = ua.AccessLevel.CurrentRead.mask
            for path in STATUS:
                node = client.get_node(ua.NodeId(path, ns))
                assert (await node.read_attribute(ua.AttributeIds.AccessLevel)).Value.Value == read, path
                assert (await node.read_attribute(ua.AttributeIds.UserAccessLevel)).Value.Value == read, path
                variant = await node.read_data_value()
                assert await _write_status(client, node.nodeid, variant.Value) == ua.StatusCodes.BadNotWritable, path
            execute = client.get_node(ua.NodeId("MoveRel_Execute", ns))
            level = (await execute.read_attribute(ua.AttributeIds.AccessLevel)).Value.Value
            assert level & ua.AccessLevel.CurrentWrite.mask
    run_async(body())


def test_the_outputs_switch_opens_status_the_name_rule_closed(thesis_project):
    # the thesis table closes Cobot.* itself (an explicit entry): the switch opens only what the
    # built-in rules close, here `Connect_Busy` (named like a status, not in the thesis table)
    # after the table's own `*_Busy` entry is opened too
    run = Running(thesis_project, limits={"@outputs": {"writable": True}, "*_Busy": {"writable": True}})
    try:
        async def body():
            async with Client(run.url) as client:
                ns = await client.get_namespace_index(run.ns_uri)
                busy = ua.NodeId("Connect_Busy", ns)
                assert await _write_status(client, busy, ua.Variant(False, ua.VariantType.Boolean)) == ua.StatusCodes.Good
                connected = ua.NodeId("Cobot.Connected", ns)
                assert await _write_status(client, connected, ua.Variant(False, ua.VariantType.Boolean)) \
                    == ua.StatusCodes.BadNotWritable
        run_async(body())
    finally:
        run.close()
