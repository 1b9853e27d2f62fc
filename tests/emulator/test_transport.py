"""TCP server and in-process link: clients, disconnects, faults, leaks, determinism, fuzz."""

from __future__ import annotations

import os
import socket
import threading

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from emulator import FaultPlan, InProcessLink, start_server
from emulator.framing import Frame, encode
from emulator.settings import EmulatorSettings

from emu_helpers import RobotSide, SyncClient, wait_until

MS = 1_000_000
QUERY = b"$TMSTA,2,00,*41\r\n"
IN_NODE = b"$TMSTA,15,00,true,Listen1,*79\r\n"


def _open_fds() -> int:
    return len(os.listdir("/proc/self/fd"))


def test_query_over_tcp(server) -> None:
    client = SyncClient(server.port)
    try:
        client.send(QUERY)
        assert client.read_frame() == IN_NODE
    finally:
        client.close()


def test_several_clients_and_no_leaks() -> None:
    threads_before = threading.active_count()
    fds_before = _open_fds()
    srv = start_server(port=0, settings=EmulatorSettings(time_scale=0.05))
    clients = [SyncClient(srv.port) for _ in range(5)]
    for i, client in enumerate(clients):
        client.send_frame("TMSCT", f"{i + 1},PTP(\"JPP\",0,0,90,0,90,{10 * i},50,100,0,false)\r\nQueueTag({i + 1})")
    for i, client in enumerate(clients):
        assert client.read_frame() == encode("TMSCT", f"{i + 1},OK")
        assert client.read_frame() == encode("TMSTA", f"01,{i + 1:02d},true")  # own tag only
    for client in clients:
        client.close()
    assert wait_until(lambda: srv.snapshot()["connections"] == [])
    srv.stop()
    assert wait_until(lambda: threading.active_count() == threads_before)
    assert _open_fds() <= fds_before


def test_disconnect_mid_motion_and_reconnect(server) -> None:
    client = SyncClient(server.port)
    client.send_frame("TMSCT", '1,PTP("JPP",0,0,90,0,90,90,100,100,0,false)\r\nQueueTag(1)')
    assert client.read_frame() == encode("TMSCT", "1,OK")
    client.close()  # mid-motion
    assert wait_until(lambda: server.snapshot()["connections"] == [])
    assert server.snapshot()["moving"] or server.snapshot()["tags"][1] in ("false", "true")
    again = SyncClient(server.port)
    try:
        again.send(QUERY)
        assert again.read_frame() == IN_NODE
        again.send_frame("TMSTA", "01,1")
        assert again.read_frame() in (encode("TMSTA", "01,1,false"), encode("TMSTA", "01,1,true"))
    finally:
        again.close()


def test_fault_refuse() -> None:
    srv = start_server(port=0, faults=FaultPlan(refuse_connections=1))
    try:
        # `refuse:N` accepts and resets (RST): depending on when the RST arrives, the client sees
        # it in connect() itself (ECONNRESET from the non-blocking connect) or at send/recv
        with pytest.raises((ConnectionError, OSError)):
            sock = socket.create_connection(("127.0.0.1", srv.port), timeout=2)
            try:
                sock.sendall(QUERY)
                if not sock.recv(100):
                    raise ConnectionResetError("closed")
            finally:
                sock.close()
        client = SyncClient(srv.port)  # the second attempt is accepted
        client.send(QUERY)
        assert client.read_frame() == IN_NODE
        client.close()
    finally:
        srv.stop()


def test_project_stop_refuses_connections() -> None:
    srv = start_server(port=0, settings=EmulatorSettings(after_exit="stop"))
    try:
        client = SyncClient(srv.port)
        client.send_frame("TMSCT", "1,ScriptExit(1)")
        assert client.read_frame() == encode("TMSCT", "1,OK")
        with pytest.raises(ConnectionError):
            client.read_frame()
        client.close()
        assert wait_until(lambda: not srv.listening)
        with pytest.raises(ConnectionRefusedError):
            socket.create_connection(("127.0.0.1", srv.port), timeout=2)
        srv.call(lambda core, now: core.robot.start_project(now))
        assert wait_until(lambda: _can_connect(srv.port))
    finally:
        srv.stop()


def _can_connect(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=1).close()
        return True
    except OSError:
        return False


def test_fault_drop_mid_motion() -> None:
    srv = start_server(port=0, faults=FaultPlan(drop_after_motion_ms=20))
    try:
        client = SyncClient(srv.port)
        client.send_frame("TMSCT", '1,PTP("JPP",0,0,90,0,90,90,100,100,0,false)')
        assert client.read_frame() == encode("TMSCT", "1,OK")
        with pytest.raises(ConnectionError):
            client.read_frame()
        client.close()
    finally:
        srv.stop()


def test_fault_corrupt_split_delay_in_process() -> None:
    link = InProcessLink(faults=FaultPlan(corrupt_checksum_every=1, split_frames_at=5, reply_delay_ms=7),
                         latency_ns=0)
    client = link.endpoint()
    client.connect()
    link.step(MS)
    client.send(QUERY)
    link.step(6 * MS)
    assert client.recv(100) == b""
    link.step(1 * MS)
    data = client.recv(100)
    assert data[:-4] == IN_NODE[:-4] and data[-4:-2] != IN_NODE[-4:-2]


def test_fault_unsolicited() -> None:
    link = InProcessLink(faults=FaultPlan(unsolicited_every_ms=100), latency_ns=0)
    client = link.endpoint()
    client.connect()
    link.step(250 * MS)
    assert client.recv(1000).count(b"90,unsolicited") == 2


def test_in_process_is_deterministic() -> None:
    def scenario() -> list:
        link = InProcessLink(latency_ns=1_234_567)
        a, b = link.endpoint(), link.endpoint()
        a.connect()
        b.connect()
        trace = []
        for i in range(3000):
            link.step(1_000_000)
            if i == 5:
                a.send(encode("TMSCT", '1,PTP("JPP",0,0,90,0,90,30,50,150,50,false)\r\nQueueTag(1)\r\n'
                                       'Line("CAP",400,-100,350,180,0,90,200,100,0,false)\r\nQueueTag(2,1)'))
            if i == 7:
                b.send(QUERY + b"garbage$TMSTA,5,01,01,*6A\r\n")
            if i == 50:
                a.send(encode("TMSCT", "2,Pause()"))
            if i == 90:
                a.send(encode("TMSCT", "3,Resume()"))
            for ep in (a, b):
                data = ep.recv(65536)
                if data:
                    trace.append((link.now_ns, id(ep) == id(a), data))
        trace.append(link.robot.snapshot()["pose"])
        return trace

    first, second = scenario(), scenario()
    assert first == second
    assert any(b"01,02,true" in item[2] for item in first[:-1])


def test_in_process_close_and_reconnect() -> None:
    link = InProcessLink(latency_ns=MS)
    client = link.endpoint()
    client.connect()
    link.step(2 * MS)
    assert client.status == "connected"
    client.close()
    link.step(2 * MS)
    assert link.robot.snapshot()["connections"] == []
    client.connect()
    link.step(2 * MS)
    client.send(QUERY)
    link.step(2 * MS)
    assert client.recv(100) == IN_NODE


def test_in_process_refused_when_project_stopped() -> None:
    link = InProcessLink(latency_ns=MS)
    link.robot.stop_project(0)
    client = link.endpoint()
    client.connect()
    link.step(2 * MS)
    assert client.status == "refused"


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=200))
def test_fuzz_server_keeps_serving(blob: bytes) -> None:
    """Random bytes on one connection: only well-formed robot frames come back, and another
    client is still served."""
    link = InProcessLink(latency_ns=0)
    noisy, other = link.endpoint(), link.endpoint()
    noisy.connect()
    other.connect()
    link.step(MS)
    noisy.send(blob)
    link.step(10_000 * MS)
    replies = noisy.recv(1 << 20)
    framer = RobotSide()
    pos = 0
    while pos < len(replies):
        used, result = framer.decode(replies[pos:])
        assert used > 0 and isinstance(result, Frame)
        pos += used
    other.send(QUERY)
    link.step(MS)
    assert other.recv(100) in (IN_NODE, b"$TMSTA,9,00,false,,*37\r\n")


def test_garbage_over_tcp_then_still_serving(server) -> None:
    noisy = SyncClient(server.port)
    noisy.send(b"\x00\xff$TMSCT,-1,zz\r\n$TMsct,2,1,,*00\r\n")
    assert noisy.read_frame() == b"$CPERR,2,01,*49\r\n"
    assert noisy.read_frame() == b"$CPERR,2,02,*4A\r\n"
    noisy.send(QUERY)
    assert noisy.read_frame() == IN_NODE
    noisy.close()


def _stepped_run(full_steps: bool) -> list:
    """A motion script, a pause and a resume over an in-process link stepped by 1 ms, with the
    pose read through a robot reference held from the start (as a view holds it) after every
    step; `full_steps` forces the full `advance_to` path on every step (no quiet steps)."""
    link = InProcessLink(latency_ns=MS)
    robot = link.robot
    client = link.endpoint()
    client.connect()
    trace = []
    for i in range(2500):
        if full_steps:
            link._quiet_until = -1
        link.step(MS)
        if i == 5:
            client.send(encode("TMSCT", '1,PTP("JPP",0,0,90,0,90,30,50,150,50,false)\r\nQueueTag(1)\r\n'
                                        'Line("CAP",400,-100,350,180,0,90,200,100,0,false)\r\nQueueTag(2,1)'))
        if i == 400:
            client.send(encode("TMSCT", "2,Pause()"))
        if i == 700:
            client.send(encode("TMSCT", "3,Resume()"))
        data = client.recv(65536)
        if data:
            trace.append((link.now_ns, data))
        if i % 7 == 0:
            trace.append((robot.executor.current_tcp().tobytes(), robot.now_ns, robot.executor.time_ns))
    trace.append(robot.snapshot())
    return trace


def test_quiet_steps_change_nothing() -> None:
    """The link lets the core's clocks lag while nothing is due (`InProcessLink._quiet_until`);
    what the client receives, when, and the pose read in between are those of a link that steps
    the core every time."""
    quiet, full = _stepped_run(False), _stepped_run(True)
    assert quiet == full
    assert any(isinstance(item[1], bytes) and b"01,02,true" in item[1] for item in quiet[:-1])
