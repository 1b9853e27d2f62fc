"""Socket FBs (sysmac.md 4, 5): the Execute protocol scan by scan, and every FB's normal and
error paths against a local TCP peer on 127.0.0.1 (the test drives both ends; no threads).

Protocol timing runs on a scripted link (fully deterministic); network behaviour on real sockets,
polled with short waits between scans only while a request is still busy.
"""

from __future__ import annotations

import copy
import random
import socket
import struct
import time
from types import SimpleNamespace

import pytest

from stdlib_helpers import MS, FBRunner, make_ctx
from stvm.runtime.values import ArrayRef
from stvm.stdlib import sockets as skt
from stvm.stdlib.sockets import (
    CONNECTING, ESTABLISHED, PEER_CLOSED, RESET, RealTcpTransport, SocketError, SocketTable,
)

CODES = {
    "out_of_range": 0x0400, "too_few_elements": 0x0407, "port_in_use": 0x2001,
    "unresolvable": 0x2002, "wrong_state": 0x2003, "timeout": 0x2006, "bad_handle": 0x2007,
    "too_many_sockets": 0x2008,
}
STATES = {"_CLOSED": 0, "_ESTABLISHED": 4, "_CLOSE_WAIT": 5, "_SYN_SENT": 2}


# --- harness ----------------------------------------------------------------------------------

def socket_value(handle: int = 0) -> SimpleNamespace:
    address = lambda: SimpleNamespace(v_portno=0, v_ipadr=b"")  # noqa: E731
    return SimpleNamespace(v_handle=handle, v_srcadr=address(), v_dstadr=address())


FB_VARIABLES = {
    "SktTCPConnect": dict(SrcTcpPort=0, DstAdr=b"127.0.0.1", DstTcpPort=0),
    "SktClearBuf": {},
    "SktGetTCPStatus": dict(TcpStatus=0, DatRcvFlag=False),
    "SktTCPSend": dict(Size=0, SendDat=None),
    "SktTCPRcv": dict(TimeOut=0, Size=0, RcvDat=None, RcvSize=0),
    "SktClose": {},
}


class Plc:
    """A RunContext advanced one scan (1 ms) at a time, and socket FB instances on it.

    `between_scans`: the transport's socket service runs at the scan boundaries (the hooks
    `RealTcpTransport.serve_between_scans` gives a VM, run by `next_scan` and `end_scan`), as in
    `stvm run` of the demo; else every FB call polls its socket itself."""

    def __init__(self, transport=None, between_scans: bool = False, **settings) -> None:
        self.ctx = make_ctx(**settings)
        self.ctx.transport = transport
        self.vm = None
        self._in_scan = False
        if between_scans:
            self.vm = SimpleNamespace(on_scan_start=[], on_scan_end=[], now_ns=0)
            transport.serve_between_scans(self.vm)
            self._start_scan()

    def _start_scan(self) -> None:
        self.vm.now_ns = self.ctx.now_ns
        for hook in self.vm.on_scan_start:
            hook(self.vm)
        self._in_scan = True

    def end_scan(self) -> None:
        """The end of the scan in progress (its queued sends go out)."""
        if self._in_scan:
            for hook in self.vm.on_scan_end:
                hook(self.vm)
            self._in_scan = False

    def refresh(self, handle: int) -> str:
        """The handle's state after the network was looked at once more."""
        if self.vm is None:
            return self.ctx.transport.poll(handle, self.ctx.now_ns)
        self.next_scan()
        return self.ctx.transport.poll(handle, self.ctx.now_ns)

    def fb(self, name: str, **inputs) -> FBRunner:
        variables = dict(Execute=False, Done=False, Busy=False, Error=False, ErrorID=0,
                         Socket=socket_value(), **FB_VARIABLES[name])
        variables.update(inputs)
        return FBRunner(name, self.ctx, **variables)

    def next_scan(self, ms: int = 1) -> None:
        if self.vm is not None:
            self.end_scan()
        self.ctx.scan += 1
        self.ctx.now_ns += ms * MS
        if self.vm is not None:
            self._start_scan()

    def execute(self, runner: FBRunner, wall_timeout_s: float = 3.0, scan_ms: int = 1, **inputs):
        """Start a request and call once per scan until it completes (the thesis pattern with
        Execute held TRUE); returns the instance at completion."""
        runner.step(Execute=True, **inputs)
        return self.complete(runner, wall_timeout_s, scan_ms)

    def complete(self, runner: FBRunner, wall_timeout_s: float = 3.0, scan_ms: int = 1):
        """Call a started request once per scan (Execute held) until it completes; returns the
        instance at completion."""
        deadline = time.monotonic() + wall_timeout_s
        while runner.Busy:
            assert time.monotonic() < deadline, "request did not complete"
            self.next_scan(scan_ms)
            runner.step()
            if runner.Busy:
                time.sleep(0.0005)
        if self.vm is not None:
            self.end_scan()
        return runner.inst

    def finish(self, runner: FBRunner) -> None:
        """The call with Execute FALSE that clears Done/Error."""
        self.next_scan()
        runner.step(Execute=False)
        assert not (runner.Done or runner.Error or runner.Busy)

    def connect(self, port: int, **inputs) -> SimpleNamespace:
        connect = self.fb("SktTCPConnect", DstTcpPort=port, **inputs)
        self.execute(connect)
        assert connect.Done, hex(connect.ErrorID)
        self.finish(connect)
        return connect.Socket


class Peer:
    """The server end: a listener on 127.0.0.1 and the connections it accepted."""

    def __init__(self) -> None:
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen(32)
        self.port = self.listener.getsockname()[1]
        self.connections: list[socket.socket] = []

    def accept(self) -> socket.socket:
        self.listener.settimeout(2.0)
        connection, _ = self.listener.accept()
        connection.settimeout(2.0)
        self.connections.append(connection)
        return connection

    def close(self) -> None:
        for connection in self.connections:
            connection.close()
        self.listener.close()


def read_exactly(connection: socket.socket, count: int) -> bytes:
    data = b""
    while len(data) < count:
        chunk = connection.recv(count - len(data))
        assert chunk, "peer closed early"
        data += chunk
    return data


def reset(connection: socket.socket) -> None:
    """Close with RST (SO_LINGER 0)."""
    connection.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    connection.close()


def wait_for_state(plc: Plc, handle: int, state: str) -> None:
    deadline = time.monotonic() + 3.0
    while plc.refresh(handle) != state:
        assert time.monotonic() < deadline, f"socket never became {state}"
        time.sleep(0.001)


@pytest.fixture
def peer():
    server = Peer()
    yield server
    server.close()


@pytest.fixture(params=["per_call", "between_scans"])
def plc(request):
    controller = Plc(RealTcpTransport(), between_scans=request.param == "between_scans")
    yield controller
    controller.ctx.transport.close_all()


# --- a scripted link: deterministic protocol timing ------------------------------------------

class ScriptedLink:
    """A link whose state and incoming bytes the test sets (what an emulator link provides)."""

    opened: list["ScriptedLink"] = []

    def __init__(self, src_port: int, host: str, port: int, now_ns: int) -> None:
        self.state = CONNECTING
        self.failure = None
        self.local_address = ("127.0.0.1", src_port or 49152)
        self.remote_address = (host, port)
        self.incoming = bytearray()
        self.sent = bytearray()
        self.closed = False
        ScriptedLink.opened.append(self)

    def poll(self, now_ns: int) -> bytes:
        data = bytes(self.incoming)
        self.incoming.clear()
        return data

    def send(self, data: bytes) -> None:
        if self.state not in (ESTABLISHED, PEER_CLOSED):
            raise SocketError("wrong_state")
        self.sent += data

    def close(self) -> None:
        self.closed = True


@pytest.fixture
def scripted():
    ScriptedLink.opened = []
    return Plc(SocketTable(ScriptedLink))


def scripted_socket(plc: Plc) -> SimpleNamespace:
    """A connected scripted socket (handle 1)."""
    connect = plc.fb("SktTCPConnect", DstTcpPort=6000)
    connect.step(Execute=True)
    ScriptedLink.opened[-1].state = ESTABLISHED
    plc.next_scan()
    connect.step()
    assert connect.Done
    plc.next_scan()
    connect.step(Execute=False)
    return connect.Socket


# --- the Execute protocol (sysmac.md 4) -------------------------------------------------------

def test_done_one_call_after_start_and_held_while_execute(scripted):
    sock = scripted_socket(scripted)
    clear = scripted.fb("SktClearBuf", Socket=sock)
    trace = []
    for execute in [False, True, True, True, False, False]:
        scripted.next_scan()
        clear.step(Execute=execute)
        trace.append((clear.Busy, clear.Done, clear.Error))
    assert trace == [(False, False, False), (True, False, False), (False, True, False),
                     (False, True, False), (False, False, False), (False, False, False)]


def test_done_for_one_call_when_execute_already_false(scripted):
    sock = scripted_socket(scripted)
    clear = scripted.fb("SktClearBuf", Socket=sock)
    trace = []
    for execute in [True, False, False, False]:
        scripted.next_scan()
        clear.step(Execute=execute)
        trace.append((clear.Busy, clear.Done))
    assert trace == [(True, False), (False, True), (False, False), (False, False)]


def test_thesis_pattern_done_seen_two_scans_later(scripted):
    """`X_Exe := TRUE` and `.Done` read above the call: started in scan n, seen in n+2."""
    sock = scripted_socket(scripted)
    clear = scripted.fb("SktClearBuf", Socket=sock)
    seen = []
    execute = False
    for scan in range(5):
        scripted.next_scan()
        seen.append(clear.Done)          # read above the call, as the thesis does
        if scan == 0:
            execute = True               # step sets X_Exe in scan 0
        clear.step(Execute=execute)
    assert seen == [False, False, True, True, True]


def test_edges_while_busy_are_ignored_and_a_new_request_needs_a_false_call(scripted):
    sock = scripted_socket(scripted)
    rcv = scripted.fb("SktTCPRcv", Socket=sock, Size=10, RcvDat=[0] * 10)
    link = ScriptedLink.opened[-1]
    for execute in [True, False, True, False, True]:   # edges while busy: ignored
        scripted.next_scan()
        rcv.step(Execute=execute)
        assert rcv.Busy
    link.incoming += b"AB"
    scripted.next_scan()
    rcv.step(Execute=True)
    assert rcv.Done and rcv.RcvSize == 2
    link.incoming += b"CD"
    scripted.next_scan()
    rcv.step(Execute=True)                              # still held: no new request
    assert rcv.Done and rcv.RcvDat[:2] == list(b"AB")
    scripted.next_scan()
    rcv.step(Execute=False)
    scripted.next_scan()
    rcv.step(Execute=True)
    assert rcv.Busy
    scripted.next_scan()
    rcv.step()
    assert rcv.Done and rcv.RcvDat[:2] == list(b"CD")


@pytest.mark.parametrize(("latency", "done_at_call"), [(0, 0), (1, 1), (2, 2), (3, 3)])
def test_min_latency_calls(latency, done_at_call):
    plc = Plc(SocketTable(ScriptedLink), skt_min_latency_calls=latency)
    ScriptedLink.opened = []
    connect = plc.fb("SktTCPConnect", DstTcpPort=6000)
    connect.step(Execute=True)
    ScriptedLink.opened[-1].state = ESTABLISHED
    for _ in range(3):
        if connect.Done:
            break
        plc.next_scan()
        connect.step()
    sock = connect.Socket
    clear = plc.fb("SktClearBuf", Socket=sock)
    calls = 0
    clear.step(Execute=True)
    while not clear.Done:
        calls += 1
        plc.next_scan()
        clear.step()
    assert calls == done_at_call


def test_error_held_then_errorid_cleared_with_error(scripted):
    close = scripted.fb("SktClose", Socket=socket_value(0))
    scripted.execute(close)
    assert close.Error and close.ErrorID == CODES["bad_handle"]
    scripted.next_scan()
    close.step()                                       # Execute still TRUE: held
    assert close.Error and close.ErrorID == CODES["bad_handle"]
    scripted.next_scan()
    close.step(Execute=False)
    assert not close.Error and close.ErrorID == 0


def test_errorid_kept_after_error_clears_with_start_only():
    plc = Plc(SocketTable(ScriptedLink), skt_errorid_reset="start_only")
    close = plc.fb("SktClose", Socket=socket_value(0))
    plc.execute(close)
    plc.finish(close)
    assert close.ErrorID == CODES["bad_handle"]
    close.step(Execute=True)                           # a new start clears it
    assert close.Busy and close.ErrorID == 0


def test_request_progresses_without_calls_by_default(scripted):
    sock = scripted_socket(scripted)
    rcv = scripted.fb("SktTCPRcv", Socket=sock, Size=10, RcvDat=[0] * 10)
    rcv.step(Execute=True)
    ScriptedLink.opened[-1].incoming += b"X"
    scripted.next_scan(ms=50)                          # the FB is not called for 49 scans
    scripted.ctx.scan += 48
    rcv.step()
    assert rcv.Done and rcv.RcvSize == 1


def test_request_cancelled_when_not_called_with_cancel_setting():
    plc = Plc(SocketTable(ScriptedLink), skt_progress_without_call="cancel")
    ScriptedLink.opened = []
    sock = scripted_socket(plc)
    rcv = plc.fb("SktTCPRcv", Socket=sock, Size=10, RcvDat=[0] * 10)
    rcv.step(Execute=True)
    plc.next_scan()
    plc.next_scan()                                    # one scan without a call
    ScriptedLink.opened[-1].incoming += b"X"
    rcv.step(Execute=True)                             # no edge: the request is gone
    assert not (rcv.Busy or rcv.Done or rcv.Error)


def test_connect_times_out_after_75_s_of_vm_time(scripted):
    connect = scripted.fb("SktTCPConnect", DstTcpPort=6000)
    connect.step(Execute=True)
    scripted.next_scan(ms=74_999)
    connect.step()
    assert connect.Busy
    scripted.next_scan(ms=1)
    connect.step()
    assert connect.Error and connect.ErrorID == CODES["timeout"]
    assert connect.Socket.v_handle == 0
    assert scripted.ctx.transport.open_count == 0      # the socket was released


def test_abandoned_connect_completes_later_and_shows_done_once(scripted):
    """sysmac.md 8 #11: a connect the thesis gave up on completes later and fills Socket."""
    connect = scripted.fb("SktTCPConnect", DstTcpPort=6000)
    connect.step(Execute=True)
    scripted.next_scan()
    connect.step(Execute=False)
    assert connect.Busy
    ScriptedLink.opened[-1].state = ESTABLISHED
    scripted.next_scan()
    connect.step()
    assert connect.Done and connect.Socket.v_handle == 1
    scripted.next_scan()
    connect.step()
    assert not connect.Done and connect.Socket.v_handle == 1


def test_transports_are_created_lazily_on_the_context():
    ctx = make_ctx()
    assert ctx.transport is None
    close = FBRunner("SktClose", ctx, Execute=True, Done=False, Busy=False, Error=False, ErrorID=0,
                     Socket=socket_value(0))
    close.step()
    assert isinstance(ctx.transport, RealTcpTransport)
    ctx.transport.close_all()


# --- `quiet`: the calls the generated code may skip (`{native quiet:Execute}`) ---------------

def state_of(runner: FBRunner):
    """Everything a call could change: the instance's variables and the implementation's state."""
    return copy.deepcopy((vars(runner.inst), vars(runner.impl)))


@pytest.mark.parametrize("after_close", ["unchanged", "zeroed"])
@pytest.mark.parametrize("name", sorted(FB_VARIABLES))
def test_a_call_with_execute_equal_to_quiet_changes_nothing(name, after_close):
    """The contract the call-site skip relies on, over random Execute sequences with the link
    connecting, receiving, closed by the peer and reset: whenever `Execute is impl.quiet`, the
    call leaves the instance and the implementation exactly as they were."""
    skipped = 0
    for seed in range(12):
        rng = random.Random(seed)
        plc = Plc(SocketTable(ScriptedLink), skt_socket_after_close=after_close)
        ScriptedLink.opened = []
        sock = scripted_socket(plc) if name != "SktTCPConnect" else socket_value()
        inputs = dict(DstTcpPort=6000) if name == "SktTCPConnect" else dict(Socket=sock)
        runner = plc.fb(name, **inputs, **{"SktTCPSend": dict(Size=2, SendDat=[1, 2]),
                                           "SktTCPRcv": dict(Size=4, RcvDat=[0] * 4)}.get(name, {}))
        for _ in range(80):
            plc.next_scan()
            link = ScriptedLink.opened[-1] if ScriptedLink.opened else None
            event = rng.random()
            if link is not None and event < 0.15:
                link.state = rng.choice([ESTABLISHED, PEER_CLOSED, RESET])
            elif link is not None and event < 0.3:
                link.incoming += b"xy"
            if rng.random() < 0.3:   # Execute held for a few scans, as the thesis's FBs hold it
                runner.inst.v_execute = not runner.inst.v_execute
            if runner.inst.v_execute is runner.impl.quiet:
                before = state_of(runner)
                runner.step()
                assert state_of(runner) == before
                skipped += 1
            else:
                runner.step()
    assert skipped > 10


# --- SktTCPConnect ---------------------------------------------------------------------------

def test_connect_fills_socket(plc, peer):
    connect = plc.fb("SktTCPConnect", DstTcpPort=peer.port)
    plc.execute(connect)
    assert connect.Done and not connect.Error and connect.ErrorID == 0
    sock = connect.Socket
    assert sock.v_handle == 1
    assert (sock.v_dstadr.v_ipadr, sock.v_dstadr.v_portno) == (b"127.0.0.1", peer.port)
    assert sock.v_srcadr.v_ipadr == b"127.0.0.1" and sock.v_srcadr.v_portno > 0
    server_side = peer.accept()
    assert server_side.getpeername()[1] == sock.v_srcadr.v_portno
    assert plc.connect(peer.port).v_handle == 2        # handles are never reused


def test_connect_refused(plc):
    closed = socket.socket()
    closed.bind(("127.0.0.1", 0))
    port = closed.getsockname()[1]
    closed.close()
    connect = plc.fb("SktTCPConnect", DstTcpPort=port)
    plc.execute(connect)
    assert connect.Error and connect.ErrorID == CODES["wrong_state"]
    assert connect.Socket.v_handle == 0
    assert plc.ctx.transport.open_count == 0


@pytest.mark.parametrize(("inputs", "settings", "code"), [
    (dict(DstTcpPort=0), {}, "out_of_range"),
    (dict(DstTcpPort=80, SrcTcpPort=0), {"skt_connect_srcport0": "error"}, "out_of_range"),
    (dict(DstTcpPort=80, DstAdr=b""), {}, "unresolvable"),
])
def test_connect_bad_inputs(inputs, settings, code):
    plc = Plc(RealTcpTransport(), **settings)
    connect = plc.fb("SktTCPConnect", **inputs)
    plc.execute(connect)
    assert connect.Error and connect.ErrorID == CODES[code]
    assert plc.ctx.transport.open_count == 0


def test_connect_source_port_in_use(plc, peer):
    connect = plc.fb("SktTCPConnect", DstTcpPort=peer.port, SrcTcpPort=peer.port)
    plc.execute(connect)
    assert connect.Error and connect.ErrorID == CODES["port_in_use"]


def test_connect_with_a_fixed_source_port(plc, peer):
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    free_port = probe.getsockname()[1]
    probe.close()
    sock = plc.connect(peer.port, SrcTcpPort=free_port)
    assert sock.v_srcadr.v_portno == free_port


def test_seventeenth_socket_fails_until_one_is_closed(plc, peer):
    sockets = [plc.connect(peer.port) for _ in range(16)]
    connect = plc.fb("SktTCPConnect", DstTcpPort=peer.port)
    plc.execute(connect)
    assert connect.Error and connect.ErrorID == CODES["too_many_sockets"]
    plc.finish(connect)
    close = plc.fb("SktClose", Socket=sockets[0])
    plc.execute(close)
    assert close.Done
    assert plc.connect(peer.port).v_handle == 17


@pytest.mark.parametrize(("setting", "handle_after"), [("unchanged", 1), ("zeroed", 0)])
def test_socket_output_after_close(setting, handle_after, peer):
    plc = Plc(RealTcpTransport(), skt_socket_after_close=setting)
    connect = plc.fb("SktTCPConnect", DstTcpPort=peer.port)
    plc.execute(connect)
    plc.finish(connect)
    close = plc.fb("SktClose", Socket=SimpleNamespace(**vars(connect.Socket)))
    plc.execute(close)
    plc.next_scan()
    connect.step(Execute=False)
    assert connect.Socket.v_handle == handle_after
    plc.ctx.transport.close_all()


# --- SktTCPSend --------------------------------------------------------------------------------

def test_send_from_the_element_given(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    data = [0] * 5 + list(b"$TMSTA,2,00,*41\r\n") + [0xEE] * 3
    send = plc.fb("SktTCPSend", Socket=sock, SendDat=ArrayRef(data, 5), Size=17)
    plc.execute(send)
    assert send.Done and not send.Error
    assert read_exactly(server_side, 17) == b"$TMSTA,2,00,*41\r\n"


@pytest.mark.parametrize(("skt_send_copy", "sent"), [("at_start", b"OLD"), ("at_service", b"NEW")])
def test_send_copies_the_data_when_the_setting_says(peer, skt_send_copy, sent):
    """`skt_send_copy` (sysmac.md 4): the bytes are taken when the request starts (default) or
    when the socket service sends them, after the ST code changed the array."""
    plc = Plc(RealTcpTransport(), skt_send_copy=skt_send_copy)
    try:
        sock = plc.connect(peer.port)
        server_side = peer.accept()
        data = list(b"OLD")
        send = plc.fb("SktTCPSend", Socket=sock, SendDat=data, Size=3)
        send.step(Execute=True)
        data[:] = list(b"NEW")
        plc.next_scan()
        send.step()
        assert send.Done
        assert read_exactly(server_side, 3) == sent
    finally:
        plc.ctx.transport.close_all()


def test_send_size_limits(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    cases = [(0, 10, None), (2000, 2000, None), (2001, 3000, "out_of_range"), (11, 10, "too_few_elements")]
    for size, elements, code in cases:
        send = plc.fb("SktTCPSend", Socket=sock, SendDat=[0x41] * elements, Size=size)
        plc.execute(send)
        assert (send.Error, send.ErrorID) == ((True, CODES[code]) if code else (False, 0)), size
    assert read_exactly(server_side, 2000) == b"A" * 2000  # only the 2000-byte send went out


def test_send_size0_error_setting(peer):
    plc = Plc(RealTcpTransport(), skt_send_size0="error")
    sock = plc.connect(peer.port)
    send = plc.fb("SktTCPSend", Socket=sock, SendDat=[0] * 4, Size=0)
    plc.execute(send)
    assert send.Error and send.ErrorID == CODES["out_of_range"]
    plc.ctx.transport.close_all()


def test_send_on_closed_and_invalid_handles(plc, peer):
    sock = plc.connect(peer.port)
    close = plc.fb("SktClose", Socket=sock)
    plc.execute(close)
    for handle in (sock.v_handle, 0, 99):
        send = plc.fb("SktTCPSend", Socket=socket_value(handle), SendDat=[1, 2], Size=2)
        plc.execute(send)
        assert send.Error and send.ErrorID == CODES["bad_handle"], handle


def test_send_works_in_close_wait(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    server_side.shutdown(socket.SHUT_WR)               # peer FIN: we are in _CLOSE_WAIT
    wait_for_state(plc, sock.v_handle, PEER_CLOSED)
    send = plc.fb("SktTCPSend", Socket=sock, SendDat=list(b"late"), Size=4)
    plc.execute(send)
    assert send.Done
    assert read_exactly(server_side, 4) == b"late"


def test_send_after_peer_reset(plc, peer):
    sock = plc.connect(peer.port)
    reset(peer.accept())
    wait_for_state(plc, sock.v_handle, RESET)
    send = plc.fb("SktTCPSend", Socket=sock, SendDat=[1], Size=1)
    plc.execute(send)
    assert send.Error and send.ErrorID == CODES["wrong_state"]


# --- SktTCPRcv ---------------------------------------------------------------------------------

def receive(plc: Plc, sock, size: int, data: list, timeout: int = 0, **kwargs):
    rcv = plc.fb("SktTCPRcv", Socket=sock, Size=size, RcvDat=data, TimeOut=timeout)
    plc.execute(rcv, **kwargs)
    return rcv


def test_partial_receives_and_untouched_elements(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    server_side.sendall(b"ABCDEFGHIJ")
    wait = time.monotonic() + 2
    while plc.ctx.transport.pending(sock.v_handle) < 10 and time.monotonic() < wait:
        plc.refresh(sock.v_handle)
        time.sleep(0.001)
    data = [0xEE] * 8
    sizes = []
    for _ in range(3):
        rcv = receive(plc, sock, 4, data)
        assert rcv.Done
        sizes.append(rcv.RcvSize)
        if rcv.RcvSize == 2:
            assert data[:4] == list(b"IJGH")          # elements after RcvSize not touched
        plc.finish(rcv)
    assert sizes == [4, 4, 2]
    assert data[4:] == [0xEE] * 4


def test_receive_into_an_element_offset(plc, peer):
    sock = plc.connect(peer.port)
    peer.accept().sendall(b"xyz")
    data = [0] * 6
    rcv = receive(plc, sock, 3, ArrayRef(data, 3))
    assert rcv.Done and data == [0, 0, 0] + list(b"xyz")[:rcv.RcvSize] + [0] * (3 - rcv.RcvSize)


def test_receive_waits_for_data_then_takes_what_is_there(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    rcv = plc.fb("SktTCPRcv", Socket=sock, Size=256, RcvDat=[0] * 256, TimeOut=0)
    rcv.step(Execute=True)
    for _ in range(20):                                 # TimeOut 0: waits forever
        plc.next_scan(ms=60_000)
        rcv.step()
        assert rcv.Busy
    server_side.sendall(b"true")
    plc.complete(rcv)
    assert rcv.Done and rcv.RcvSize == 4 and bytes(rcv.RcvDat[:4]) == b"true"


def test_receive_timeout_on_the_vm_clock(plc, peer):
    sock = plc.connect(peer.port)
    peer.accept()
    rcv = plc.fb("SktTCPRcv", Socket=sock, Size=10, RcvDat=[0] * 10, TimeOut=5)  # 0.5 s
    rcv.step(Execute=True)
    plc.next_scan(ms=499)
    rcv.step()
    assert rcv.Busy
    plc.next_scan(ms=1)
    rcv.step()
    assert rcv.Error and rcv.ErrorID == CODES["timeout"]


def test_receive_timeout0_error_if_empty_setting(peer):
    plc = Plc(RealTcpTransport(), skt_rcv_timeout0="error_if_empty")
    sock = plc.connect(peer.port)
    peer.accept()
    rcv = receive(plc, sock, 10, [0] * 10)
    assert rcv.Error and rcv.ErrorID == CODES["timeout"]
    plc.ctx.transport.close_all()


def test_receive_after_peer_close_gives_data_then_zero(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    server_side.sendall(b"bye")
    server_side.shutdown(socket.SHUT_WR)
    wait_for_state(plc, sock.v_handle, PEER_CLOSED)
    rcv = receive(plc, sock, 10, [0] * 10)
    assert rcv.Done and rcv.RcvSize == 3
    plc.finish(rcv)
    rcv = receive(plc, sock, 10, [0] * 10)
    assert rcv.Done and rcv.RcvSize == 0


def test_receive_after_peer_close_error_setting(peer):
    plc = Plc(RealTcpTransport(), skt_rcv_peer_closed="error")
    sock = plc.connect(peer.port)
    peer.accept().shutdown(socket.SHUT_WR)
    wait_for_state(plc, sock.v_handle, PEER_CLOSED)
    rcv = receive(plc, sock, 10, [0] * 10)
    assert rcv.Error and rcv.ErrorID == CODES["wrong_state"]
    plc.ctx.transport.close_all()


def test_peer_reset_mid_receive(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    server_side.sendall(b"part")
    rcv = receive(plc, sock, 10, [0] * 10)
    assert rcv.Done and rcv.RcvSize == 4
    plc.finish(rcv)
    rcv = plc.fb("SktTCPRcv", Socket=sock, Size=10, RcvDat=[0] * 10, TimeOut=0)
    rcv.step(Execute=True)
    plc.next_scan()
    rcv.step()
    assert rcv.Busy
    reset(server_side)
    plc.complete(rcv)
    assert rcv.Error and rcv.ErrorID == CODES["wrong_state"]


def test_receive_buffer_overflow_is_discarded(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    server_side.sendall(bytes(range(256)) * 47)        # 12,032 bytes
    server_side.shutdown(socket.SHUT_WR)
    wait_for_state(plc, sock.v_handle, PEER_CLOSED)
    assert plc.ctx.transport.pending(sock.v_handle) == 9_000
    received = b""
    while True:
        data = [0] * 2000
        rcv = receive(plc, sock, 2000, data)
        plc.finish(rcv)
        if rcv.RcvSize == 0:
            break
        received += bytes(data[:rcv.RcvSize])
    assert received == (bytes(range(256)) * 47)[:9_000]


@pytest.mark.parametrize(("size", "elements", "code"), [
    (0, 10, "out_of_range"), (2001, 3000, "out_of_range"), (11, 10, "too_few_elements"),
])
def test_receive_bad_sizes(plc, peer, size, elements, code):
    sock = plc.connect(peer.port)
    rcv = receive(plc, sock, size, [0] * elements)
    assert rcv.Error and rcv.ErrorID == CODES[code]


def test_receive_on_closed_handle(plc, peer):
    sock = plc.connect(peer.port)
    plc.execute(plc.fb("SktClose", Socket=sock))
    rcv = receive(plc, sock, 10, [0] * 10)
    assert rcv.Error and rcv.ErrorID == CODES["bad_handle"]


def test_close_while_receiving_fails_the_receive(plc, peer):
    sock = plc.connect(peer.port)
    rcv = plc.fb("SktTCPRcv", Socket=sock, Size=10, RcvDat=[0] * 10, TimeOut=0)
    rcv.step(Execute=True)
    plc.execute(plc.fb("SktClose", Socket=sock))
    plc.next_scan()
    rcv.step()
    assert rcv.Error and rcv.ErrorID == CODES["bad_handle"]


# --- SktClearBuf ---------------------------------------------------------------------------

def test_clear_discards_unread_and_keeps_later_bytes(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    server_side.sendall(b"stale reply")
    deadline = time.monotonic() + 2
    while plc.ctx.transport.pending(sock.v_handle) < 11 and time.monotonic() < deadline:
        plc.refresh(sock.v_handle)
        time.sleep(0.001)
    clear = plc.fb("SktClearBuf", Socket=sock)
    plc.execute(clear)
    assert clear.Done and plc.ctx.transport.pending(sock.v_handle) == 0
    server_side.sendall(b"new")
    rcv = receive(plc, sock, 10, [0] * 10)
    assert rcv.Done and bytes(rcv.RcvDat[:rcv.RcvSize]) == b"new"[:rcv.RcvSize]


def test_clear_on_invalid_handle(plc):
    clear = plc.fb("SktClearBuf", Socket=socket_value(5))
    plc.execute(clear)
    assert clear.Error and clear.ErrorID == CODES["bad_handle"]


# --- SktGetTCPStatus -------------------------------------------------------------------------

def status(plc: Plc, sock) -> FBRunner:
    runner = plc.fb("SktGetTCPStatus", Socket=sock)
    plc.execute(runner)
    return runner


def test_status_through_the_connection_life(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    first = status(plc, sock)
    assert first.Done and first.TcpStatus == STATES["_ESTABLISHED"] and not first.DatRcvFlag
    server_side.sendall(b"x")
    deadline = time.monotonic() + 2
    while not status(plc, sock).DatRcvFlag:
        assert time.monotonic() < deadline
        time.sleep(0.001)
    server_side.shutdown(socket.SHUT_WR)
    wait_for_state(plc, sock.v_handle, PEER_CLOSED)
    after_fin = status(plc, sock)
    assert after_fin.TcpStatus == STATES["_CLOSE_WAIT"] and after_fin.DatRcvFlag
    plc.execute(plc.fb("SktClose", Socket=sock))
    closed = status(plc, sock)
    assert closed.Done and closed.TcpStatus == STATES["_CLOSED"] and not closed.DatRcvFlag


def test_status_after_peer_reset_is_closed(plc, peer):
    sock = plc.connect(peer.port)
    reset(peer.accept())
    wait_for_state(plc, sock.v_handle, RESET)
    assert status(plc, sock).TcpStatus == STATES["_CLOSED"]


def test_status_of_never_valid_handles(plc):
    for handle in (0, 42):
        runner = status(plc, socket_value(handle))
        assert runner.Error and runner.ErrorID == CODES["bad_handle"]


def test_status_of_closed_handle_error_setting(peer):
    plc = Plc(RealTcpTransport(), skt_status_closed_handle="error")
    sock = plc.connect(peer.port)
    plc.execute(plc.fb("SktClose", Socket=sock))
    runner = status(plc, sock)
    assert runner.Error and runner.ErrorID == CODES["bad_handle"]


def test_status_uses_the_configured_enum_values(peer):
    values = {name: 100 + index for index, name in enumerate(skt.STATE_NAMES.values())}
    values.update({"_CLOSED": 100, "_ESTABLISHED": 104})
    plc = Plc(RealTcpTransport(), connection_state_values=values)
    sock = plc.connect(peer.port)
    assert status(plc, sock).TcpStatus == 104
    plc.ctx.transport.close_all()


# --- SktClose ----------------------------------------------------------------------------------

def test_close_sends_fin_and_invalidates_the_handle(plc, peer):
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    server_side.sendall(b"unread")
    close = plc.fb("SktClose", Socket=sock)
    plc.execute(close)
    assert close.Done
    assert server_side.recv(10) == b""                  # FIN, not RST
    again = plc.fb("SktClose", Socket=sock)
    plc.execute(again)
    assert again.Error and again.ErrorID == CODES["bad_handle"]
    assert plc.ctx.transport.open_count == 0


def test_close_all_closes_every_socket(plc, peer):
    for _ in range(3):
        plc.connect(peer.port)
    server_sides = [peer.accept() for _ in range(3)]
    plc.ctx.transport.close_all()
    assert plc.ctx.transport.open_count == 0
    assert all(side.recv(1) == b"" for side in server_sides)


def test_no_fb_raises_on_transport_surprises(plc):
    """A transport failure never escapes an FB as a Python exception."""
    class Broken(SocketTable):
        def poll(self, handle, now_ns):
            raise OSError("network is down")
    plc.ctx.transport = Broken(ScriptedLink)
    for name in ("SktClearBuf", "SktGetTCPStatus", "SktClose"):
        runner = plc.fb(name, Socket=socket_value(1))
        plc.execute(runner)
        assert runner.Error


# --- settings without a test of their own above ------------------------------------------------

def test_send_max_setting(peer):
    plc = Plc(RealTcpTransport(), skt_send_max=10)
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    for size, error in ((10, False), (11, True)):
        send = plc.fb("SktTCPSend", Socket=sock, SendDat=[0x42] * 20, Size=size)
        plc.execute(send)
        assert (send.Error, send.ErrorID) == ((True, CODES["out_of_range"]) if error else (False, 0)), size
        plc.finish(send)
    assert read_exactly(server_side, 10) == b"B" * 10
    plc.ctx.transport.close_all()


def test_receive_timeout_unit_setting(peer):
    plc = Plc(RealTcpTransport(), skt_rcv_timeout_unit_ns=MS)   # TimeOut counts ms, not 0.1 s
    sock = plc.connect(peer.port)
    peer.accept()
    rcv = plc.fb("SktTCPRcv", Socket=sock, Size=10, RcvDat=[0] * 10, TimeOut=5)
    rcv.step(Execute=True)
    plc.next_scan(ms=4)
    rcv.step()
    assert rcv.Busy
    plc.next_scan(ms=1)
    rcv.step()
    assert rcv.Error and rcv.ErrorID == CODES["timeout"]
    plc.ctx.transport.close_all()


def test_error_codes_table_setting(plc):
    codes = dict(CODES, bad_handle=0x7777)
    custom = Plc(RealTcpTransport(), skt_error_codes=codes)
    for controller, expected in ((plc, CODES["bad_handle"]), (custom, 0x7777)):
        send = controller.fb("SktTCPSend", Socket=socket_value(0), SendDat=[1], Size=1)
        controller.execute(send)
        assert send.Error and send.ErrorID == expected
    custom.ctx.transport.close_all()


# --- the socket service between scans (RealTcpTransport.serve_between_scans) ----------------------

class CountingSocket:
    """A socket proxy counting the calls that reach the OS (receives and sends)."""

    def __init__(self, sock: socket.socket) -> None:
        self._sock = sock
        self.calls = 0

    def __getattr__(self, name):
        attribute = getattr(self._sock, name)
        if name in ("recv", "recv_into", "send"):
            def counted(*args):
                self.calls += 1
                return attribute(*args)
            return counted
        return attribute


def serviced_plc() -> Plc:
    return Plc(RealTcpTransport(), between_scans=True)


def test_a_waiting_receive_makes_no_system_call_in_the_scan(peer):
    plc = serviced_plc()
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    link = plc.ctx.transport._sockets[sock.v_handle].link
    counting = link._sock = CountingSocket(link._sock)
    rcv = plc.fb("SktTCPRcv", Socket=sock, Size=10, RcvDat=[0] * 10, TimeOut=0)
    rcv.step(Execute=True)
    for _ in range(20):
        plc.next_scan()
        rcv.step()
    assert rcv.Busy and counting.calls == 0     # nothing readable: no recv, in or between scans
    server_side.sendall(b"ok")
    plc.complete(rcv)
    assert rcv.Done and bytes(rcv.RcvDat[:2]) == b"ok"
    plc.ctx.transport.close_all()


def test_fbs_see_what_arrived_before_the_scan_and_sends_leave_after_it(peer):
    plc = serviced_plc()
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    server_side.sendall(b"late")
    time.sleep(0.05)                                    # in the OS buffer, not yet serviced
    status_now = plc.fb("SktGetTCPStatus", Socket=sock)
    status_now.step(Execute=True)
    plc.ctx.transport.poll(sock.v_handle, plc.ctx.now_ns)   # an FB's poll does no I/O
    assert plc.ctx.transport.pending(sock.v_handle) == 0
    plc.next_scan()                                     # the service reads before this scan
    status_now.step()
    assert status_now.Done and status_now.DatRcvFlag
    send = plc.fb("SktTCPSend", Socket=sock, SendDat=list(b"ping"), Size=4)
    send.step(Execute=True)
    server_side.settimeout(0.05)
    with pytest.raises(socket.timeout):
        server_side.recv(4)                             # queued until the scan ends
    plc.end_scan()
    server_side.settimeout(2.0)
    assert read_exactly(server_side, 4) == b"ping"
    plc.ctx.transport.close_all()


def test_a_new_socket_on_a_reused_descriptor_is_watched_afresh(peer):
    plc = serviced_plc()
    first = plc.connect(peer.port)
    peer.accept()
    plc.execute(plc.fb("SktClose", Socket=first))
    second = plc.connect(peer.port)                     # the OS may give it the same descriptor
    server_side = peer.accept()
    server_side.sendall(b"new")
    rcv = receive(plc, second, 10, [0] * 10)
    assert rcv.Done and bytes(rcv.RcvDat[:rcv.RcvSize]) == b"new"[:rcv.RcvSize]
    plc.ctx.transport.close_all()


def test_a_reset_found_when_sending_after_the_scan_clears_the_buffer(peer):
    plc = serviced_plc()
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    reset(server_side)
    time.sleep(0.05)
    link = plc.ctx.transport._sockets[sock.v_handle].link
    plc.ctx.transport._sockets[sock.v_handle].received += b"old"
    link.send(b"x")                                     # queued; the reset shows at the flush
    plc.ctx.transport._to_flush.add(sock.v_handle)
    plc.end_scan()
    assert link.state == RESET and plc.ctx.transport.pending(sock.v_handle) == 0
    plc.next_scan()
    assert status(plc, sock).TcpStatus == STATES["_CLOSED"]


def test_the_service_time_is_kept_per_scan(peer):
    plc = serviced_plc()
    plc.connect(peer.port)
    scans = plc.ctx.transport.service_ns
    before = len(scans)
    for _ in range(5):
        plc.next_scan()
    assert len(scans) == before + 5
    plc.ctx.transport.close_all()


def test_a_send_queued_in_the_scan_of_the_close_still_goes_out_before_the_fin(peer):
    plc = serviced_plc()
    sock = plc.connect(peer.port)
    server_side = peer.accept()
    plc.next_scan()
    send = plc.fb("SktTCPSend", Socket=sock, SendDat=list(b"last"), Size=4)
    send.step(Execute=True)                             # queued, not sent yet
    plc.fb("SktClose", Socket=sock).step(Execute=True)  # the same scan
    assert read_exactly(server_side, 4) == b"last"
    assert server_side.recv(1) == b""


# --- a busy SktTCPRcv with nothing to read (`SktTCPRcv.call`'s shortcut) ---------------------

def _receive_run(timeout: int, shortcut: bool) -> tuple[list, int]:
    """A receive request polled every scan for 400 scans, bytes arriving now and then, Execute
    toggled at random and the link reset near the end, on a table whose service runs between the
    scans (`poll_all` before each scan): the instance and implementation after every call, and
    how many calls took the shortcut (`quiet_receive` TRUE)."""
    rng = random.Random(timeout)
    ScriptedLink.opened = []
    plc = Plc(SocketTable(ScriptedLink))
    sock = scripted_socket(plc)
    table = plc.ctx.transport
    table.between_scans = True
    quiet = [0]
    probe = table.quiet_receive

    def counted(handle: int) -> bool:
        answer = shortcut and probe(handle)
        quiet[0] += answer
        return answer
    table.quiet_receive = counted
    runner = plc.fb("SktTCPRcv", Socket=sock, Size=4, RcvDat=[0] * 4, TimeOut=timeout)
    history = []
    for scan in range(400):
        plc.next_scan()
        link = ScriptedLink.opened[-1]
        if rng.random() < 0.03:
            link.incoming += b"xy"
        if scan == 380:
            link.state = RESET
        table.poll_all(plc.ctx.now_ns)
        if rng.random() < 0.08:
            runner.inst.v_execute = not runner.inst.v_execute
        runner.step()
        history.append(state_of(runner))
    return history, quiet[0]


@pytest.mark.parametrize("timeout", [0, 1])
def test_a_waiting_receive_changes_what_the_full_call_changes(timeout):
    """With nothing buffered and the link unchanged, a busy SktTCPRcv returns after noting the
    call: every call leaves the instance and its state as the full call does (TimeOut 0: wait for
    ever; 1: time out after 100 ms, the default unit, when nothing came)."""
    fast, taken = _receive_run(timeout, True)
    full, _ = _receive_run(timeout, False)
    assert fast == full
    assert taken > 50
