"""CBT_Connect (thesis Annex A1, st_src/CBT_Connect.st) against the TM emulator over loopback.

Per scan: Busy/Done/Error/ErrorID of the FB, Cobot.Connected.  Scan numbers are relative to the
scan that first sees Execute (R_TRIG); distances that the FB code fixes are asserted exactly,
the ones that depend on the wall clock (socket round trips) only in order.

Scan arithmetic used below (sysmac.md 8.8/8.9): a state change requested by the algorithm in
scan n (ToError_Sts) moves the state diagram in n+1 (Busy still TRUE) and shows Error in n+2;
socket FB results are read above the calls, i.e. one scan late.
"""

from __future__ import annotations

import pytest

from thesis_harness import (CHECK_LISTEN, CLOSE, LISTEN_OK, RESET, Runner, closed_port, make_bench_fixture,
                            tm_frame, unanswered_port)

bench = make_bench_fixture()

KEYS = ("Busy", "Done", "Error", "ErrorID")


def conn_runner(b) -> Runner:
    b.runner.watch.update({k: f"T.Conn.{k}" for k in KEYS + ("FB_step", "FB_status", "ErrorDescrip")})
    return b.runner


def start_connect(b, time_out: int = 100) -> int:
    conn_runner(b)
    b.vm.set("T.Port", b.port)
    b.vm.set("T.TimeOut", time_out)
    b.vm.set("T.ConnExecute", True)
    return b.vm.scan_count


def scan_step_first(runner: Runner, step: int, start: int) -> int:
    return runner.first(lambda s: s["FB_step"] == step, start).scan


# ---------------------------------------------------------------------------------------- normal


def test_connect_supervise_and_close(bench):
    """Execute -> Busy -> the Listen-node check frame -> Connected (FB stays Busy, supervising);
    Execute FALSE -> socket closed -> Done for exactly one scan (Execute already FALSE)."""
    b = bench(None, do_connect=False)
    r = conn_runner(b)
    s0 = start_connect(b)
    r.run_until(lambda s: s["Connected"], max_scans=3000, what="Connected")
    # Busy from the scan after the R_TRIG scan (state 1 'Reset' keeps Busy FALSE), never Done
    first = r.since(s0)
    assert (first[0]["Busy"], first[0]["Done"], first[0]["Error"]) == (False, False, False)
    assert all(s["Busy"] and not s["Done"] and not s["Error"] for s in first[1:])
    # exactly one frame sent, the fixed status request of thesis l.4369, equal to the frame
    # computed from tm_protocol.md §2 / §5.1 (TMSTA, DATA "00")
    assert b.wait_rx(1) == [CHECK_LISTEN]
    assert CHECK_LISTEN == tm_frame("TMSTA", "00")
    assert b.emulator.tx() == [LISTEN_OK]
    # supervision: 2.5 s of VM time, still Busy and connected, no further frame (only status)
    b.scans(2500)
    assert b.vm.get("T.Conn.Busy") and b.vm.get("T.Cobot.Connected")
    assert b.rx() == [CHECK_LISTEN]
    assert len(b.emulator.snapshot()["connections"]) == 1
    assert b.vm.format("T.Conn.LastConnTime") != "DT#1970-01-01-00:00:00"   # set once in step 90
    # Execute FALSE: F_TRIG -> step 100 in the same scan: Connected FALSE at once
    s1 = b.vm.scan_count
    b.vm.set("T.ConnExecute", False)
    b.scans(1)
    assert not b.vm.get("T.Cobot.Connected") and b.vm.get("T.Conn.FB_step") == 100
    r.run_until(lambda s: s["Done"], max_scans=50, what="Done")
    b.scans(3)
    runs = r.runs(KEYS, s1)
    assert [state for state, _, _ in runs] == [(True, False, False, 0), (False, True, False, 0),
                                               (False, False, False, 0)]
    assert runs[1][2] == 1, "Done lasts one scan when Execute is already FALSE (sysmac.md 8.9)"
    # the emulator saw the connection close
    deadline = b.vm.scan_count + 2000
    while b.emulator.snapshot()["connections"] and b.vm.scan_count < deadline:
        b.scans(1)
    assert b.emulator.snapshot()["connections"] == []


# ----------------------------------------------------------------------- 16#15 timeout range


@pytest.mark.parametrize("time_out", [0, 9, 301, 65535])
def test_timeout_out_of_range_16_15(bench, time_out):
    """Step 15: Time_Out outside 10~300 -> 16#15, no connection attempt.  Exact scans:
    R_TRIG scan (Busy FALSE), step 10, step 15 (ToError_Sts), state 2->3 (Busy still TRUE), Error."""
    b = bench(None, do_connect=False)
    r = conn_runner(b)
    s0 = start_connect(b, time_out)
    b.scans(8)
    seq = [tuple(s[k] for k in KEYS) for s in r.since(s0)]
    assert seq[:5] == [(False, False, False, 0), (True, False, False, 0), (True, False, False, 0),
                       (True, False, False, 0), (False, False, True, 0x15)]
    assert all(x == (False, False, True, 0x15) for x in seq[4:])
    assert b.vm.get("T.Conn.ErrorDescrip") == b"Timeout range: 10~300 seconds"
    assert b.rx() == [] and b.emulator.snapshot()["connections"] == []
    # Execute FALSE: state 4 'Error deactive' - Error FALSE at once, ErrorID kept
    b.vm.set("T.ConnExecute", False)
    b.scans(2)
    assert tuple(r.trace[-1][k] for k in KEYS) == (False, False, False, 0x15)


# ---------------------------------------------------------------------- 16#20 refused


def stop_project(em) -> None:
    """Stop the emulated robot's project: its Listen-node port closes (tm_protocol.md §1.2)."""
    import time
    em.server.call(lambda core, now: core.robot.stop_project(now))
    deadline = time.monotonic() + 2
    while em.server.listening and time.monotonic() < deadline:
        time.sleep(0.005)
    assert not em.server.listening


@pytest.mark.parametrize("how", ["closed_port", "emulator_project_stopped"])
def test_connection_refused_16_20(bench, how):
    """Connect refused (RST to the SYN): SktTCPConnect.Error -> 16#20 'Connection Error'."""
    if how == "closed_port":
        b = bench(None, robot="port", port=closed_port(), do_connect=False)
    else:
        b = bench(None, do_connect=False)
        stop_project(b.emulator)
    r = conn_runner(b)
    s0 = start_connect(b)
    r.run_until(lambda s: s["Error"], max_scans=2000, what="Error")
    b.scans(3)
    assert r.states(KEYS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x20)]
    assert b.vm.get("T.Conn.ErrorDescrip") == b"Connection Error"
    assert not any(s["Connected"] for s in r.trace)
    assert b.rx() == []


@pytest.mark.parametrize("fault", ["refuse", "stop:0"])
def test_emulator_refusal_is_a_tcp_refusal(bench, fault):
    """A robot refusing connections (tm_protocol.md §1.2: no project running -> connection
    refused; docs/emulator.md `refuse`, `stop:MS`) answers the SYN with RST, so SktTCPConnect
    fails and CBT_Connect reports 16#20.  The emulator keeps its listener open and resets the
    accepted socket instead (`refuse`; and `stop:0` for the first second, F2): the kernel has
    completed the handshake, so CBT_Connect ended with 16#20, 16#50 or 16#60 depending on timing
    (FIDELITY_FINDINGS.md F1, F2; fixed: the listener is closed while the robot refuses).
    Deterministic part, checked here: a plain connect() must be refused."""
    import socket
    b = bench(None, faults=[fault], do_connect=False)
    with pytest.raises(ConnectionRefusedError):
        sock = socket.create_connection(("127.0.0.1", b.port), timeout=2)
        sock.close()


# ---------------------------------------------------------------------- 16#21 timeout


@pytest.mark.parametrize("time_out, scans_after_step20", [
    (10, 1004),    # 10 * 100000000 ns = 1.000 s (sysmac.md 8.7: 0.1 s units, not seconds)
    (43, 10),      # 4.3e9 wraps to 5032704 ns = 5.03 ms (sysmac.md 8.7)
    (21, 2104),    # 2.1 s: the largest value that does not overflow
    (100, 1415),   # 1e10 wraps in 32 bits to 1410065408 ns = 1.410 s (sysmac.md 8.7)
])
def test_connection_timeout_16_21(bench, time_out, scans_after_step20):
    """SYNs unanswered: TON_TimeOut (PT = NanoSecToTime(Time_Out*100000000), DINT arithmetic)
    expires on the VM clock.  Step 20 first runs one scan after FB_step becomes 20; the TON starts
    there; Q at start+PT (rounded up to the 1 ms scan); ToError one scan later (Q read above the
    call); Error two scans after that (sysmac.md 8.9)."""
    with unanswered_port() as port:
        b = bench(None, robot="port", port=port, do_connect=False)
        r = conn_runner(b)
        s0 = start_connect(b, time_out)
        r.run_until(lambda s: s["Error"], max_scans=3000, what="Error")
        s20 = scan_step_first(r, 20, s0)
        err = r.first(lambda s: s["Error"], s0)
        assert err.scan - s20 == scans_after_step20
        assert err["ErrorID"] == 0x21 and b.vm.get("T.Conn.ErrorDescrip") == b"TimeOut Error"
        assert r.states(KEYS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x21)]


@pytest.mark.parametrize("time_out", [22, 30, 42, 300])
def test_timeout_overflow_negative_pt_16_21_and_socket_leak(bench, time_out):
    """sysmac.md 8.7: Time_Out 22..42 (and 300, accepted by the 10~300 check) make the UINT*DINT
    product wrap negative: TON Q at its first call -> 16#21 'TimeOut Error' four scans after
    FB_step becomes 20, although the robot is there.  sysmac.md 8.11: the connect that completed
    meanwhile is never closed (the socket stays open at the robot)."""
    b = bench(None, do_connect=False)
    r = conn_runner(b)
    s0 = start_connect(b, time_out)
    r.run_until(lambda s: s["Error"], max_scans=200, what="Error")
    s20 = scan_step_first(r, 20, s0)
    assert r.first(lambda s: s["Error"], s0).scan - s20 == 4
    assert b.vm.get("T.Conn.ErrorID") == 0x21
    assert not b.vm.get("T.Cobot.Connected")
    # the abandoned connect completed and was never closed: the robot still holds the socket
    import time
    deadline = time.monotonic() + 2
    while len(b.emulator.snapshot()["connections"]) != 1 and time.monotonic() < deadline:
        b.scans(10)
    b.scans(200)
    assert len(b.emulator.snapshot()["connections"]) == 1
    assert b.vm.get("T.Cobot.Socket.Handle") != 0
    assert b.rx() == []


# ---------------------------------------------------------------------- 16#70 not a cobot


def test_not_in_listen_node_16_70(bench):
    import emulator
    b = bench(None, settings=emulator.EmulatorSettings(start_in_node=False), do_connect=False)
    r = conn_runner(b)
    s0 = start_connect(b)
    r.run_until(lambda s: s["Error"], max_scans=3000, what="Error")
    b.scans(2)
    assert r.states(KEYS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x70)]
    assert b.vm.get("T.Conn.ErrorDescrip") == b"Device is not a Cobot"
    assert b.rx() == [CHECK_LISTEN]
    assert b.emulator.tx() == [tm_frame("TMSTA", "00,false,")]   # tm_protocol.md §5.1
    assert not any(s["Connected"] for s in r.trace)


def test_cperr_reply_to_status_request_stays_busy(bench):
    """Step 70 only looks for 'true' / 'false': any other reply (here a CPERR) leaves the FB Busy
    in step 70 for ever, never Connected (no receive timeout, sysmac.md 8.6)."""
    def robot(f, i):
        return [tm_frame("CPERR", "04")]
    b = bench(None, robot="fake", responder=robot, do_connect=False)
    r = conn_runner(b)
    s0 = start_connect(b)
    r.run_until(lambda s: s["FB_step"] == 70, max_scans=3000, what="step 70")
    b.scans(2000)
    assert b.fake.frames == [CHECK_LISTEN]
    assert r.states(KEYS, s0) == [(False, False, False, 0), (True, False, False, 0)]
    assert all(s["FB_step"] == 70 and not s["Connected"] for s in r.trace[-1900:])


# ---------------------------------------------------------------------- 16#90 lost


def test_connection_lost_16_90(bench):
    """The robot closes (FIN): the next 1 s status poll (Timer_1, step 90 -> 80) reads
    _CLOSE_WAIT -> 16#90 'Socket disconnected', Connected FALSE, LastLostTime set; Error two
    scans after Connected falls."""
    b = bench(None, robot="fake")
    r = conn_runner(b)
    s_lost = b.vm.scan_count
    b.fake.push(CLOSE)
    r.run_until(lambda s: s["Error"], max_scans=3000, what="Error")
    down = r.first(lambda s: not s["Connected"], s_lost)
    err = r.first(lambda s: s["Error"], s_lost)
    assert err.scan - down.scan == 2
    assert err.now_ms - r.at(s_lost).now_ms <= 1000 + 10, "status is polled every 1000 ms"
    assert err["ErrorID"] == 0x90 and b.vm.get("T.Conn.ErrorDescrip") == b"Socket disconnected"
    assert r.states(("Busy", "Error", "Connected"), s_lost) == [(True, False, True), (True, False, False),
                                                                (False, True, False)]
    assert b.vm.format("T.Conn.LastLostTime") != "DT#1970-01-01-00:00:00"


def test_connection_reset_not_detected(bench):
    """sysmac.md 8.10: only _CLOSE_WAIT is checked; after a peer RST the state is _CLOSED and
    the FB keeps polling with Connected TRUE (original bug, kept)."""
    b = bench(None, robot="fake")
    r = conn_runner(b)
    s_lost = b.vm.scan_count
    b.fake.push(RESET)
    b.scans(2600)
    assert all(s["Busy"] and s["Connected"] and not s["Error"] for s in r.since(s_lost))
    assert b.vm.get("T.Conn.Get_TCP_Status.TcpStatus") == 0   # _CLOSED (BSD order, sysmac.md 5)


# ---------------------------------------------------------------------- Execute dropped


def test_execute_dropped_while_connecting_16_100(bench):
    """Execute FALSE before the socket exists: F_TRIG -> step 100 closes handle 0 -> SktClose
    error -> 16#100 'TCP Close Error', shown for one scan only (Execute FALSE: state 3 -> 4 in the
    same scan), ErrorID kept in state 4."""
    b = bench(None, do_connect=False)
    r = conn_runner(b)
    s0 = start_connect(b)
    b.scans(2)                       # R_TRIG scan + step 10
    b.vm.set("T.ConnExecute", False)
    b.scans(12)
    runs = r.runs(KEYS, s0)
    assert [state for state, _, _ in runs] == [(False, False, False, 0), (True, False, False, 0),
                                               (False, False, True, 0x100), (False, False, False, 0x100)]
    assert runs[2][2] == 1
    assert b.vm.get("T.Conn.ErrorDescrip") == b"TCP Close Error"
    assert not any(s["Connected"] for s in r.trace)
