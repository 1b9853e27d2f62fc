"""Fuzz (hypothesis, fixed seed, bounded) of OPC UA write values and sampling parameters with
asyncua's client over loopback: every answer is a documented status, nothing raises inside the
server, and the server still serves afterwards (issue 34 "Fuzz tests")."""

from __future__ import annotations

import math

from asyncua import Client, ua
from hypothesis import HealthCheck, given, settings, strategies as st

from opcua_helpers import run_async

PATHS = ["MoveAbs_Param.Speed", "MoveAbs_Param.TargetPosition.X", "Connect_AddressIP", "MoveRel_Execute",
         "MoveRel_Param.MovementCommand", "Connect_Time_Out", "Cobot.Connected", "Connect_LastConnTime"]

WRITE_STATUSES = {ua.StatusCodes.Good, ua.StatusCodes.BadOutOfRange, ua.StatusCodes.BadTypeMismatch,
                  ua.StatusCodes.BadNotWritable, ua.StatusCodes.BadWriteNotSupported,
                  ua.StatusCodes.BadIndexRangeInvalid}

_VALUES = st.one_of(
    st.tuples(st.just(ua.VariantType.Boolean), st.booleans()),
    st.tuples(st.just(ua.VariantType.Int64), st.integers(-(1 << 63), (1 << 63) - 1)),
    st.tuples(st.just(ua.VariantType.UInt16), st.integers(0, 65535)),
    st.tuples(st.just(ua.VariantType.Float), st.floats(width=32)),
    st.tuples(st.just(ua.VariantType.Double), st.floats()),
    st.tuples(st.just(ua.VariantType.String), st.text(max_size=300)),
)
_WRITES = st.lists(st.tuples(st.sampled_from(PATHS), _VALUES, st.sampled_from([None, None, None, "0", "1:0", "x"])),
                   min_size=1, max_size=12)
_INTERVALS = st.lists(st.one_of(st.floats(), st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -1.0, 1e300])),
                      min_size=1, max_size=4)


@settings(max_examples=6, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
@given(writes=_WRITES, intervals=_INTERVALS)
def test_fuzzed_writes_and_sampling_intervals_get_documented_statuses(running, capfd, writes, intervals):
    async def body():
        async with Client(running.url) as client:
            ns = await client.get_namespace_index(running.ns_uri)
            items = [ua.WriteValue(NodeId=ua.NodeId(path, ns), AttributeId=ua.AttributeIds.Value, IndexRange=rng,
                                   Value=ua.DataValue(ua.Variant(value, kind)))
                     for path, (kind, value), rng in writes]
            statuses = await client.uaclient.write(ua.WriteParameters(NodesToWrite=items))
            assert len(statuses) == len(items)
            for status, (path, (kind, value), rng) in zip(statuses, writes):
                assert status.value in WRITE_STATUSES, (path, kind, value, rng, status)
                if kind in (ua.VariantType.Float, ua.VariantType.Double) and not math.isfinite(value):
                    assert not status.is_good(), (path, value)   # NaN/inf never lands
            sub = await client.create_subscription(50, _Quiet())
            node = client.get_node(ua.NodeId("MoveAbs_Param.Speed", ns))
            for interval in intervals:
                try:
                    await sub.subscribe_data_change(node, sampling_interval=interval)
                except ua.UaStatusCodeError as exc:   # asyncua raises the item's Bad status
                    assert exc.code == ua.StatusCodes.BadInvalidArgument and math.isnan(interval)
            await sub.delete()
            # still serving: a read answers with a value
            assert isinstance(await node.read_value(), int)
    run_async(body())
    err = capfd.readouterr().err
    assert "Traceback" not in err and "BadInternalError" not in err and "BadUnexpectedError" not in err, err[-2000:]


class _Quiet:
    def datachange_notification(self, *args):
        pass
