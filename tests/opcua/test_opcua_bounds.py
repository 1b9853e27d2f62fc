"""The OPC UA server bounded before and after login (issue 34 item 5): hostile clients get the
protocol's error and the server keeps serving; every limit is settable in `[opcua.limits]`."""

from __future__ import annotations

import asyncio
import math
import socket
import struct
import subprocess
import sys
import time

import pytest
from asyncua import Client, ua
from asyncua.common.subscription import Subscription
from asyncua.ua import uaerrors

from opcua_helpers import THESIS, Running, run_async
from stvm.opcua.config import OpcUaConfigError, ServerLimits, limits_from, revise_interval

NS_PATH = "@Runtime.ScanCount"


def _rss_kb() -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise AssertionError("no VmRSS")


def _endpoint(url: str) -> tuple[str, int]:
    host_port = url.split("//", 1)[1].rstrip("/")
    host, port = host_port.rsplit(":", 1)
    return host, int(port)


def _error_of(sock: socket.socket) -> tuple[int, str] | None:
    """The ERR message's status and reason the server sent before closing (None: just closed)."""
    sock.settimeout(10)
    data = b""
    try:
        while True:
            part = sock.recv(65536)
            if not part:
                break
            data += part
    except (ConnectionResetError, TimeoutError, socket.timeout):
        pass
    if not data.startswith(b"ERRF"):
        return None
    status = struct.unpack_from("<I", data, 8)[0]
    (length,) = struct.unpack_from("<i", data, 12)
    return status, data[16:16 + max(length, 0)].decode()


async def _still_serves(url: str, ns_uri: str) -> int:
    async with Client(url) as client:
        ns = await client.get_namespace_index(ns_uri)
        return await client.get_node(ua.NodeId(NS_PATH, ns)).read_value()


def test_a_chunk_header_claiming_2_gib_is_refused_without_buffering_its_body(running):
    host, port = _endpoint(running.url)
    before = _rss_kb()
    refused = []
    for _ in range(10):
        with socket.create_connection((host, port)) as sock:
            sock.sendall(b"HELF" + struct.pack("<I", 2**31))
            sent = 0
            try:
                junk = b"\0" * (1 << 20)
                while sent < 20 << 20:          # 20 MiB of body, as the attack sent
                    sock.sendall(junk)
                    sent += len(junk)
            except (BrokenPipeError, ConnectionResetError):
                pass
            refused.append(_error_of(sock))
    grown_mb = (_rss_kb() - before) / 1024
    assert all(r is not None and r[0] == ua.StatusCodes.BadTcpMessageTooLarge for r in refused), refused
    assert grown_mb < 20, f"the server's process grew by {grown_mb:.0f} MB"
    assert run_async(_still_serves(running.url, running.ns_uri)) >= 0


@pytest.mark.parametrize("frame, status", [
    (b"GET / HTTP/1.1\r\nHost: x\r\n\r\n", ua.StatusCodes.BadTcpMessageTypeInvalid),
    (b"HELF" + struct.pack("<I", 4), ua.StatusCodes.BadTcpMessageTypeInvalid),         # shorter than its header
    (b"MSGC" + struct.pack("<I", 1000) + b"\0" * 992, ua.StatusCodes.BadTcpMessageTooLarge),  # chunks before login
    (b"OPNF" + struct.pack("<I", 40000) + b"\0" * 100, ua.StatusCodes.BadTcpMessageTooLarge),  # big chunk before login
])
def test_malformed_frames_get_the_protocol_error(running, frame, status):
    host, port = _endpoint(running.url)
    with socket.create_connection((host, port)) as sock:
        sock.sendall(frame)
        assert _error_of(sock)[0] == status
    assert run_async(_still_serves(running.url, running.ns_uri)) >= 0


def test_a_connection_that_never_logs_in_is_closed(thesis_project):
    run = Running(thesis_project, opcua={"limits": {"login_timeout": 0.5}})
    try:
        host, port = _endpoint(run.url)
        with socket.create_connection((host, port)) as sock:
            start = time.monotonic()
            sock.settimeout(10)
            assert sock.recv(100) == b""      # closed by the server
            assert time.monotonic() - start < 8
    finally:
        run.close()


def test_sessions_subscriptions_and_items_per_session_are_capped(thesis_project):
    run = Running(thesis_project, opcua={"limits": {"max_sessions": 2, "max_subscriptions_per_session": 2,
                                                    "max_monitored_items_per_session": 5}})

    class Quiet:
        def datachange_notification(self, *args):
            pass

    async def body():
        async with Client(run.url) as one, Client(run.url) as two:
            with pytest.raises(uaerrors.BadTooManySessions):
                async with Client(run.url):
                    pass
            ns = await one.get_namespace_index(run.ns_uri)
            subs = [await one.create_subscription(50, Quiet()) for _ in range(2)]
            with pytest.raises(uaerrors.BadTooManySubscriptions):
                await one.create_subscription(50, Quiet())
            nodes = [one.get_node(ua.NodeId(path, ns)) for path in
                     ("@Runtime.ScanCount", "@Runtime.Time", "@Runtime.Paused", "@Runtime.Clock", "Cobot.Connected",
                      "Connect_Execute", "Connect_Done", "Connect_Busy")]
            results = await subs[0].subscribe_data_change(nodes, queuesize=1)
            refused = [r for r in results if isinstance(r, ua.StatusCode)]
            assert len(results) - len(refused) == 5
            assert {r.value for r in refused} == {ua.StatusCodes.BadTooManyMonitoredItems}
            # the other session has its own allowance
            ns2 = await two.get_namespace_index(run.ns_uri)
            sub = await two.create_subscription(50, Quiet())
            assert isinstance(await sub.subscribe_data_change(two.get_node(ua.NodeId("@Runtime.ScanCount", ns2))), int)
    try:
        run_async(body())
    finally:
        run.close()


def test_nan_and_infinite_intervals_and_wrong_argument_counts(running, capfd):
    class Quiet:
        def datachange_notification(self, *args):
            pass

    async def body():
        async with Client(running.url) as client:
            ns = await client.get_namespace_index(running.ns_uri)
            count = client.get_node(ua.NodeId("@Runtime.ScanCount", ns))
            params = ua.CreateSubscriptionParameters(RequestedPublishingInterval=math.nan, RequestedLifetimeCount=300,
                                                     RequestedMaxKeepAliveCount=10, PublishingEnabled=True)
            nan_sub = Subscription(client.uaclient, params, Quiet())
            assert (await nan_sub.init()).RevisedPublishingInterval == ServerLimits().min_publishing_interval
            with pytest.raises(uaerrors.BadInvalidArgument):
                await nan_sub.subscribe_data_change(count, sampling_interval=math.nan)
            params = ua.CreateSubscriptionParameters(RequestedPublishingInterval=math.inf, RequestedLifetimeCount=300,
                                                     RequestedMaxKeepAliveCount=10, PublishingEnabled=True)
            sub = Subscription(client.uaclient, params, Quiet())
            assert (await sub.init()).RevisedPublishingInterval == ServerLimits().max_interval
            handle = await sub.subscribe_data_change(count, sampling_interval=math.inf)
            assert isinstance(handle, int)
            handle = await sub.subscribe_data_change(count, sampling_interval=-math.inf)
            assert isinstance(handle, int)
            runtime = client.get_node(ua.NodeId("@Runtime", ns))
            with pytest.raises(uaerrors.BadTooManyArguments):
                await runtime.call_method(f"{ns}:Scan", ua.Variant(1, ua.VariantType.UInt32),
                                          ua.Variant(2, ua.VariantType.UInt32))
            with pytest.raises(uaerrors.BadArgumentsMissing):
                await runtime.call_method(f"{ns}:Scan")
            with pytest.raises(uaerrors.BadTooManyArguments):
                await runtime.call_method(f"{ns}:Pause", ua.Variant(1, ua.VariantType.UInt32))
            return await count.read_value()
    assert run_async(body()) >= 0
    assert "Traceback" not in capfd.readouterr().err


def test_revised_intervals():
    assert revise_interval(math.nan, 10, 1000) is None
    assert revise_interval(-1, 10, 1000) == 10 and revise_interval(0, 10, 1000) == 10
    assert revise_interval(-math.inf, 10, 1000) == 10
    assert revise_interval(math.inf, 10, 1000) == 1000
    assert revise_interval(50, 10, 1000) == 50


def test_limits_are_settable_and_checked():
    assert limits_from(None, "w") == ServerLimits()
    limits = limits_from({"max_connections": 5, "login_timeout": 2}, "w")
    assert limits.max_connections == 5 and limits.login_timeout == 2.0
    for bad in ({"max_connections": 0}, {"max_connections": 1.5}, {"login_timeout": float("nan")},
                {"max_chunk_size": 100}, {"max_connections": True}, {"nonsense": 1},
                {"max_message_size": 9000, "max_chunk_size": 10000}):
        with pytest.raises(OpcUaConfigError):
            limits_from(bad, "stvm.toml [opcua] limits")


def test_a_busy_port_is_one_line(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        result = subprocess.run([sys.executable, "-m", "stvm", "run", *THESIS, "--duration", "10ms",
                                 "--opcua", f"opc.tcp://127.0.0.1:{port}"],
                                capture_output=True, text=True, timeout=120)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    lines = [line for line in result.stderr.splitlines() if "OPC UA" in line]
    assert lines == [f"stvm: error: cannot serve OPC UA on opc.tcp://127.0.0.1:{port}: the port is in use "
                     f"(another server listens there; choose another port: --opcua opc.tcp://HOST:PORT)"]


def test_requests_past_max_pending_requests_wait_instead_of_closing_the_connection(thesis_project):
    # asyncua's client sends many requests without waiting (load_data_type_definitions sends
    # hundreds): past the queue's bound the server stops reading the socket until one is answered
    run = Running(thesis_project, opcua={"limits": {"max_pending_requests": 4}})
    try:
        async def body():
            async with Client(run.url) as client:
                ns = await client.get_namespace_index(run.ns_uri)
                node = client.get_node(ua.NodeId("Connect_Dest_PortIP", ns))
                values = await asyncio.gather(*[node.read_browse_name() for _ in range(120)])
                assert [v.Name for v in values] == ["Connect_Dest_PortIP"] * 120
                assert await node.read_value() == await node.read_value()   # the same session goes on
        run_async(body())
    finally:
        run.close()
