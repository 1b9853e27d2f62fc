"""End to end through the core: the ST-written FBs (R_TRIG, F_TRIG, SR, RS, CTU, CTD, CTUD), the
Omron pin aliases, timers on the VM clock, the thesis checksum idiom and a socket round trip in ST.

One load for the whole module (several PROGRAMs in one file, all in the default task); each test
starts a fresh VM and drives inputs between scans with `vm[path] = value`.
"""

from __future__ import annotations

import socket
import time
from pathlib import Path

import pytest

from stdlib_helpers import MS  # noqa: F401  (puts the checkout on sys.path)

import stvm
from stvm.settings import SysmacSettings

SOURCE = r"""
PROGRAM PEdges
VAR
    clk : BOOL;
    rq, fq : BOOL;
    r : R_TRIG;
    f : F_TRIG;
END_VAR
r(CLK := clk, Q => rq);
f(CLK := clk, Q => fq);
END_PROGRAM

PROGRAM PBistables
VAR
    s, r : BOOL;
    q_sr, q_rs, q_sr_omron, q_rs_omron : BOOL;
    sr1, sr2 : SR;
    rs1, rs2 : RS;
END_VAR
sr1(S1 := s, R := r, Q1 => q_sr);
rs1(S := s, R1 := r, Q1 => q_rs);
sr2(Set1 := s, Reset := r, Q1 => q_sr_omron);
rs2(Set := s, Reset1 := r, Q1 => q_rs_omron);
END_PROGRAM

PROGRAM PCounters
VAR
    up, down, reset, load : BOOL;
    pv : INT := 3;
    cu : CTU;
    cd : CTD;
    cud : CTUD;
    cu_omron : CTU;
    cd_omron : CTD;
    cud_omron : CTUD;
    cu_q, cd_q, cud_qu, cud_qd : BOOL;
    cu_cv, cd_cv, cud_cv, omron_cu_cv, omron_cd_cv, omron_cud_cv : INT;
END_VAR
cu(CU := up, R := reset, PV := pv, Q => cu_q, CV => cu_cv);
cd(CD := down, LD := load, PV := pv, Q => cd_q, CV => cd_cv);
cud(CU := up, CD := down, R := reset, LD := load, PV := pv, QU => cud_qu, QD => cud_qd, CV => cud_cv);
cu_omron(CU := up, Reset := reset, PV := pv, CV => omron_cu_cv);
cd_omron(CD := down, Load := load, PV := pv, CV => omron_cd_cv);
cud_omron(CU := up, CD := down, Reset := reset, Load := load, PV := pv, CV => omron_cud_cv);
END_PROGRAM

PROGRAM PTimers
VAR
    run : BOOL;
    on_delay : TON;
    off_delay : TOF;
    pulse : TP;
    ton_q, tof_q, tp_q : BOOL;
    ton_et, tof_et, tp_et : TIME;
END_VAR
on_delay(In := run, PT := T#30ms, Q => ton_q, ET => ton_et);
off_delay(IN := run, PT := T#20ms, Q => tof_q, ET => tof_et);
pulse(IN := run, PT := T#20ms, Q => tp_q, ET => tp_et);
END_PROGRAM

PROGRAM PChecksum
VAR
    frame_body : STRING[50] := 'TMSTA,2,00,';
    bytes : ARRAY[0..63] OF BYTE;
    count : UINT;
    i : INT;
    checksum_text : STRING[4];
    frame : STRING[80];
    value_text : STRING[24];
    parsed : UINT := 7;
    now_dt : DT;
    start_dt : DT;
    pt : TIME;
END_VAR
(* thesis lines 2297-2331: XOR of the bytes between '$' and '*'; the loop reads one past the text *)
count := ToAryByte(In := frame_body, Order := _eBYTE_ORDER#_LOW_HIGH, AryOut := bytes[0]);
FOR i := 1 TO LEN(frame_body) DO
    bytes[0] := bytes[0] XOR bytes[i];
END_FOR;
checksum_text := BYTE_TO_STRING(bytes[0]);
frame := CONCAT('$$', frame_body, '*', checksum_text, '$R$L');
value_text := RealToFormatString(In := -45.6, Exponent := FALSE, Sign := TRUE, MinLen := 1, DecPlace := 0);
parsed := STRING_TO_UINT('12x');   (* instruction error: parsed keeps its value *)
now_dt := GetTime();
start_dt := SecToDt(0);
pt := NanoSecToTime(UINT#10 * 100000000);
END_PROGRAM

PROGRAM PSocket
VAR
    port : UINT;
    connect_exe, send_exe, rcv_exe, close_exe : BOOL;
    tcp_connect : SktTCPConnect;
    tcp_send : SktTCPSend;
    tcp_rcv : SktTCPRcv;
    tcp_close : SktClose;
    tcp_status : SktGetTCPStatus;
    sock : _sSOCKET;
    status : _eCONNECTION_STATE;
    tx : ARRAY[0..255] OF BYTE;
    rx : ARRAY[0..255] OF BYTE;
    tx_size, rx_size : UINT;
    reply : STRING[256];
    closed_by_peer : BOOL;
END_VAR
tcp_connect(Execute := connect_exe, SrcTcpPort := 0, DstAdr := '127.0.0.1', DstTcpPort := port,
            Socket => sock);
tx_size := LEN('hello');
ToAryByte(In := 'hello', Order := _eBYTE_ORDER#_LOW_HIGH, AryOut := tx[0]);
tcp_send(Execute := send_exe, Socket := sock, SendDat := tx[0], Size := tx_size);
tcp_rcv(Execute := rcv_exe, Socket := sock, TimeOut := 0, Size := 256, RcvDat := rx[0],
        RcvSize => rx_size);
IF tcp_rcv.Done THEN
    reply := AryToString(rx[0], rx_size);
END_IF;
tcp_status(Execute := NOT (tcp_status.Done OR tcp_status.Error), Socket := sock, TcpStatus => status);
closed_by_peer := status = _CLOSE_WAIT;
tcp_close(Execute := close_exe, Socket := sock);
END_PROGRAM
"""


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    path = Path(tmp_path_factory.mktemp("st_blocks")) / "blocks.st"
    path.write_text(SOURCE)
    return stvm.load([str(path)], settings=SysmacSettings(dialect="sysmac"))   # Omron's conversions


def drive(vm, program: str, inputs: dict, outputs: list[str], rows):
    """rows: (input values..., expected output values...) per scan."""
    for number, row in enumerate(rows):
        for name, value in zip(inputs, row):
            vm[f"{program}.{name}"] = value
        vm.scan()
        actual = tuple(vm[f"{program}.{name}"] for name in outputs)
        assert actual == tuple(row[len(inputs):]), f"scan {number}: {dict(zip(outputs, actual))}"


def test_edges(project):
    vm = project.start(scan="10ms")
    drive(vm, "PEdges", ["clk"], ["rq", "fq"], [
        (True, True, False),      # rtrig_first_call = fire
        (True, False, False),
        (False, False, True),
        (False, False, False),
        (True, True, False),
    ])


def test_bistables_and_omron_pins(project):
    vm = project.start()
    drive(vm, "PBistables", ["s", "r"], ["q_sr", "q_rs", "q_sr_omron", "q_rs_omron"], [
        (False, False, False, False, False, False),
        (True, False, True, True, True, True),
        (False, False, True, True, True, True),
        (True, True, True, False, True, False),     # SR set-dominant, RS reset-dominant
        (False, True, False, False, False, False),
    ])


def test_counters_with_iec_and_omron_pins(project):
    vm = project.start()
    inputs = ["up", "down", "reset", "load"]
    outputs = ["cu_cv", "cu_q", "cd_cv", "cd_q", "cud_cv", "cud_qu", "cud_qd",
               "omron_cu_cv", "omron_cd_cv", "omron_cud_cv"]
    drive(vm, "PCounters", inputs, outputs, [
        # up down reset load | cu_cv cu_q cd_cv cd_q cud_cv qu qd | omron cu cd cud
        (False, False, False, True, 0, False, 3, False, 3, True, False, 0, 3, 3),
        (True, False, False, False, 1, False, 3, False, 4, True, False, 1, 3, 4),
        (True, False, False, False, 1, False, 3, False, 4, True, False, 1, 3, 4),   # no edge
        (False, True, False, False, 1, False, 2, False, 3, True, False, 1, 2, 3),
        (True, False, False, False, 2, False, 2, False, 4, True, False, 2, 2, 4),
        (False, True, False, False, 2, False, 1, False, 3, True, False, 2, 1, 3),
        (True, False, False, False, 3, True, 1, False, 4, True, False, 3, 1, 4),
        (False, True, False, False, 3, True, 0, True, 3, True, False, 3, 0, 3),
        (False, False, False, False, 3, True, 0, True, 3, True, False, 3, 0, 3),
        (True, True, False, False, 4, True, -1, True, 3, True, False, 4, -1, 3),    # both edges: CTUD holds
        (False, False, True, False, 0, False, -1, True, 0, False, True, 0, -1, 0),
    ])


def test_counter_limits(project):
    vm = project.start()
    vm["PCounters.cu.CV"] = 32767
    vm["PCounters.cd.CV"] = -32768
    vm["PCounters.pv"] = 32767
    for up in (True, False, True):
        vm["PCounters.up"] = up
        vm["PCounters.down"] = up
        vm.scan()
    assert vm["PCounters.cu_cv"] == 32767 and vm["PCounters.cd_cv"] == -32768


def test_timers_on_the_virtual_clock(project):
    vm = project.start(scan="10ms")
    ms = 1_000_000
    drive(vm, "PTimers", ["run"], ["ton_q", "ton_et", "tof_q", "tof_et", "tp_q", "tp_et"], [
        (True, False, 0, True, 0, True, 0),
        (True, False, 10 * ms, True, 0, True, 10 * ms),
        (True, False, 20 * ms, True, 0, False, 20 * ms),
        (True, True, 30 * ms, True, 0, False, 20 * ms),
        (False, False, 0, True, 0, False, 0),
        (False, False, 0, True, 10 * ms, False, 0),
        (False, False, 0, False, 20 * ms, False, 0),
    ])


def test_thesis_checksum_and_omron_functions(project):
    vm = project.start(start_dt_ns=1_700_000_000 * 1_000_000_000)
    vm.scan()
    vm.scan()
    assert vm["PChecksum.count"] == 12                       # 11 text bytes + NUL
    assert vm["PChecksum.checksum_text"] == b"41"            # sysmac.md 6: TMSTA,2,00, -> 16#41
    assert vm["PChecksum.frame"] == b"$TMSTA,2,00,*41\r\n"
    assert vm["PChecksum.value_text"] == b"-46"
    assert vm["PChecksum.parsed"] == 7                       # error: the assignment was skipped
    assert vm["PChecksum.start_dt"] == 0
    assert vm["PChecksum.pt"] == 1_000_000_000               # UINT#10 * 100000000 fits a DINT
    assert vm["PChecksum.now_dt"] == 1_700_000_000 * 1_000_000_000 + vm.ctx.now_ns - vm.ctx.now_ns % 1_000_000


def scan_until(vm, path: str, wall_timeout_s: float = 3.0) -> None:
    deadline = time.monotonic() + wall_timeout_s
    while not vm[path]:
        assert time.monotonic() < deadline, f"{path} never became TRUE"
        vm.scan()
        time.sleep(0.0005)


def test_socket_round_trip_in_st(project):
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    listener.settimeout(2.0)
    vm = project.start(scan="1ms")
    try:
        vm["PSocket.port"] = listener.getsockname()[1]
        vm["PSocket.connect_exe"] = True
        scan_until(vm, "PSocket.tcp_connect.Done")
        assert vm["PSocket.sock.Handle"] == 1
        server_side, _ = listener.accept()
        server_side.settimeout(2.0)
        vm["PSocket.send_exe"] = True
        scan_until(vm, "PSocket.tcp_send.Done")
        assert server_side.recv(16) == b"hello"
        server_side.sendall(b"true$")
        vm["PSocket.rcv_exe"] = True
        scan_until(vm, "PSocket.tcp_rcv.Done")
        assert vm["PSocket.reply"] == b"true$" and vm["PSocket.rx_size"] == 5
        server_side.shutdown(socket.SHUT_WR)
        scan_until(vm, "PSocket.closed_by_peer")
        vm["PSocket.close_exe"] = True
        scan_until(vm, "PSocket.tcp_close.Done")
        assert server_side.recv(16) == b""
        server_side.close()
    finally:
        vm.close()
        listener.close()
    assert vm.ctx.transport.open_count == 0


def test_settings_reach_the_generated_stdlib(tmp_path):
    from stvm.settings import SysmacSettings
    path = tmp_path / "first_call.st"
    path.write_text("PROGRAM Main\nVAR r : R_TRIG; x : BOOL; END_VAR\nr(CLK := TRUE, Q => x);\nEND_PROGRAM\n")
    vm = stvm.load([str(path)], SysmacSettings(rtrig_first_call="no_fire")).start()
    vm.scan()
    assert vm["Main.x"] is False
