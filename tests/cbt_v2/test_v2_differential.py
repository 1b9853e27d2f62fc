"""Differential tests: each original bug of the thesis library that V2 fixes, run as the same
scenario on V1 (st_src/, restored, unchanged) and V2 (st_src/cbt_v2/): V1 shows the bug, V2 does not.

Bug list (issue 14; st_src/README.md "Original bugs kept on purpose", sysmac.md section 8): two-digit
checksum (8.2), connect time-out without overflow (8.7), coordinates with configurable decimals
(8.13), quoted data formats (ERRATA Q1), receive using the received size (8.3), socket closed on
every error path (8.11), WaitingReturn cleared when the connection drops (8.10), port as UINT
(Table 6.2.1), MoveCircle speed range (README '+' row); and two more found while writing V2:
PrecisePositioning sent as disablePrecise (l.2189-2190 against Table 5.3.2.3 and l.471-473), and
Pause()/Resume() whose reply is never read (8.12) with a checksum below 16#10 (FIDELITY_FINDINGS).

Lockstep runs where the emulator can play the robot; a scripted robot over loopback
(thesis_harness.FakeRobot) where the bug needs robot behaviour the emulator has no fault for
(a reply split at a chosen byte, a TCP reset).
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

import emulator
import stvm
from core_helpers import SYSMAC
from robotlibs_helpers import ST_SRC, V2, Cell, free_high_port, load_library, script_of, tm_frame
from thesis_harness import (CHECK_LISTEN, LISTEN_OK, RESET, FakeRobot, Runner, frame_checksum, harness_project,
                            thesis_frame, tmsct_reply)
from v2_harness import V2Bench, move_params, v2_project

TARGET = (417.0, -122.0, 340.0, 180.0, 0.0, 90.0)


def v1_params(cmd_id=2, movement="PTP", fmt="CPP_Abs", target=TARGET, speed=50, accel=200, blend=None,
              precise=False) -> dict:
    p = {"CommandID": cmd_id, "MovementCommand": movement, "DataFormat": fmt, "Speed": speed,
         "AccelTime": accel, "BlendingEnable": blend is not None, "BlendingValue": blend or 0,
         "PrecisePositioning": precise}
    p.update({f"TargetPosition.{k}": v for k, v in zip(("X", "Y", "Z", "RX", "RY", "RZ"), target)})
    return p


def v2_params(**kw) -> dict:
    return move_params(**{"target": TARGET, "precise": False, **kw})


class V1Bench(Cell):
    """The thesis FBs (tests/thesis harness program T) in lockstep, connected."""

    def __init__(self, project=None, connect: bool = True, time_out: int = 100, **cell) -> None:
        super().__init__(project or harness_project(), **cell)
        self.set("T.Port", 5890)
        self.set("T.TimeOut", time_out)
        if connect:
            self.set("T.ConnExecute", True)
            self.until(lambda: self.get("T.Cobot.Connected") or self.get("T.Conn.Error"), 5000, "V1 connect")

    def move(self, inst: str, params: dict, max_scans: int = 20000) -> dict:
        self.set_many(f"T.{inst}Param", params)
        self.set(f"T.{inst}Execute", True)
        try:
            self.until(lambda: self.get(f"T.{inst}.Done") or self.get(f"T.{inst}.Error"), max_scans, "end")
        except AssertionError:
            pass
        return {k: self.get(f"T.{inst}.{k}") for k in ("Busy", "Done", "Error", "ErrorID", "FB_step")}


@pytest.fixture
def benches():
    made = []

    def add(bench):
        made.append(bench)
        return bench
    yield add
    for b in made:
        b.close()


# ------------------------------------------------------------------------- 8.2 two-digit checksum


def one_digit_v1_segment() -> dict:
    """A blended PTP whose V1 frame has a checksum below 16#10 (sysmac.md 8.2)."""
    from thesis_harness import pose_text
    for x in range(410, 425):
        for z in range(330, 356):
            p = v1_params(target=(float(x), -122.0, float(z), 180.0, 0.0, 90.0), blend=50)
            script = f'PTP("CPP",{pose_text(p[f"TargetPosition.{k}"] for k in ("X", "Y", "Z", "RX", "RY", "RZ"))},50,200,50,false)'
            if frame_checksum(thesis_frame(2, script)) < 0x10:
                return p
    raise AssertionError("no one-digit segment")


def test_checksum_two_digits(benches):
    p1 = one_digit_v1_segment()
    v1 = benches(V1Bench())
    end = v1.move("Abs", p1, 3000)
    assert v1.rx()[1][-5:-2] != b"*" and v1.rx()[1][-4:-3] == b"*"      # ',*H\r\n': one digit
    assert v1.tx()[-1] == tm_frame("CPERR", "01") and end["Busy"] and not end["Done"]
    target = tuple(p1[f"TargetPosition.{k}"] for k in ("X", "Y", "Z", "RX", "RY", "RZ"))
    v2 = benches(V2Bench("Abs"))
    v2.start("Abs", v2_params(target=target, blend=50))
    assert v2.finish("Abs")["Done"]
    assert v2.rx()[1][-6:-4] == b",*" and all(c in b"0123456789ABCDEF" for c in v2.rx()[1][-4:-2])
    assert not any(f.startswith(b"$CPERR") for f in v2.tx())


# ------------------------------------------------------------------------- 8.7 connect time-out


def test_connect_timeout_in_seconds_without_overflow(benches):
    """Time_Out 300 is inside 10~300; V1 computes NanoSecToTime(300*100000000) in 32 bits: a
    negative PT, so the time-out fires before the (present) robot has answered."""
    v1 = benches(V1Bench(time_out=300))
    assert v1.get("T.Conn.Error") and v1.get("T.Conn.ErrorID") == 0x21 and not v1.get("T.Cobot.Connected")
    assert v1.get("T.Conn.TON_TimeOut.PT") < 0
    v2 = benches(V2Bench(connect=False))
    v2.set("T.TimeOut", 300)
    v2.connect()
    assert v2.get("T.Conn.ConnectTimer.PT") == 300 * 10**9


# ------------------------------------------------------------------------- 8.13 decimals


def test_coordinates_with_decimals(benches):
    target = (417.4, -122.3, 340.6, 180.0, 0.0, 90.0)
    v1 = benches(V1Bench())
    assert v1.move("Abs", v1_params(target=target))["Done"]
    v2 = benches(V2Bench("Abs"))
    v2.start("Abs", v2_params(target=target))
    assert v2.finish("Abs")["Done"]
    assert v1.pose()[:3] == pytest.approx([417.0, -122.0, 341.0], abs=0.02)     # whole millimetres
    assert v2.pose()[:3] == pytest.approx([417.4, -122.3, 340.6], abs=0.02)     # (IK to 0.01 mm)


# ------------------------------------------------------------------------- ERRATA Q1 quoted formats


@pytest.fixture(scope="module")
def v1_as_printed():
    """V1 with the printed data-format separators (ERRATA Q1 rows at l.4956/l.4964 not applied):
    CBT_MoveAbsolute sends PTP(CPP,...)."""
    import tempfile
    from thesis_harness import FB_FILES, HARNESS_ST
    folder = Path(tempfile.mkdtemp(prefix="stvm-v1-printed-"))
    text = (ST_SRC / "CBT_MoveAbsolute.st").read_text(encoding="utf-8")
    assert text.count("'(\"',str_DataFormat,'\",'") == 2
    (folder / "CBT_MoveAbsolute.st").write_text(text.replace("'(\"',str_DataFormat,'\",'", "'(',str_DataFormat,','"),
                                                encoding="utf-8")
    (folder / "Harness.st").write_text(HARNESS_ST, encoding="utf-8")
    files = [str(folder / f) if f == "CBT_MoveAbsolute.st" else str(ST_SRC / f) for f in FB_FILES]
    return stvm.load(files + [str(folder / "Harness.st")], settings=SYSMAC)   # the thesis's Omron code


def test_quoted_data_formats(benches, v1_as_printed):
    v1 = benches(V1Bench(v1_as_printed))
    end = v1.move("Abs", v1_params())
    assert script_of(v1.rx()[1])[1].startswith("PTP(CPP,")
    assert end["Error"] and end["ErrorID"] == 0x80                     # ' Command rejected'
    v2 = benches(V2Bench("Abs"))
    v2.start("Abs", v2_params())
    assert v2.finish("Abs")["Done"]
    assert script_of(v2.rx()[1])[1].startswith('PTP("CPP",')


# ------------------------------------------------------------------------- 8.3 received size


def split_robot(first_tag: int, real_sent: threading.Event):
    """A scripted robot: OK to every script. First motion: 50 ms later ListenSend data and the tag
    notification in one segment. Second motion: a notification of another tag (15) split after
    14 bytes, and the motion's own tag only 1.5 s later (`real_sent` is set then)."""
    motions = []

    def responder(frame: bytes, index: int) -> list:
        if frame == CHECK_LISTEN:
            return [LISTEN_OK]
        ident, script = script_of(frame)
        tag = int(script.rsplit("QueueTag(", 1)[1].split(",")[0])
        motions.append(tag)
        own = tm_frame("TMSTA", f"01,{tag:02d},true")
        if len(motions) == 1:
            return [tmsct_reply(f"{ident},OK"), 0.05, tm_frame("TMSTA", "90,Hello World") + own]
        other = tm_frame("TMSTA", "01,15,true")

        def later():
            time.sleep(1.5)
            real_sent.set()
            robot.push(own)
        threading.Thread(target=later, daemon=True).start()
        return [tmsct_reply(f"{ident},OK"), 0.1, other[:14], 0.1, other[14:]]
    robot = FakeRobot(responder)
    return robot


def run_real(project, port: int, moves: list[tuple[str, dict]], inst: str, version: int, real_sent) -> list[bool]:
    """Run `moves` one after the other on a VM over loopback; returns, per move, whether its Done
    came before the robot sent the motion's real tag notification."""
    vm = project.start(scan="1ms")
    r = Runner(vm, {"Done": f"T.{inst}.Done", "Error": f"T.{inst}.Error", "Connected": "T.Cobot.Connected"})
    try:
        vm.set("T.Port", port)
        if version == 1:
            vm.set("T.TimeOut", 100)
        vm.set("T.ConnExecute", True)
        r.run_until(lambda s: s["Connected"], 5000, "connected")
        early = []
        for params in moves:
            for key, value in params[1].items():
                vm.set(f"T.{inst}Param.{key}", value)
            vm.set(f"T.{inst}Execute", True)
            # bounded by wall time, not by scans: the robot sends the real notification 1.5 s
            # (wall) later, and a fast VM runs 20,000 virtual 1 ms scans in less than that
            r.run_until(lambda s: s["Done"] or s["Error"], 10_000_000, "move end", timeout_s=10)
            assert r.trace[-1]["Done"], r.trace[-1].values
            early.append(not real_sent.is_set())
            vm.set(f"T.{inst}Execute", False)
            r.run_for(5)
        return early
    finally:
        vm.close()


def test_receive_uses_the_received_size():
    """V1 converts 256 bytes, not RcvSize: the start of another tag's notification ('$TMSTA,10,01,0',
    14 bytes) is followed by the stale rest of the first motion's longer read, which holds
    'TMSTA', '3' and 'true', so V1 reports the second motion Done although its tag has not come;
    V2 assembles the real frame (tag 15: not its own) and waits."""
    event1 = threading.Event()
    with split_robot(3, event1) as robot:
        early = run_real(harness_project(), robot.port, [("Abs", v1_params(cmd_id=3)), ("Abs", v1_params(cmd_id=3))],
                         "Abs", 1, event1)
    assert early == [True, True]                     # the second Done came before its tag: the bug
    event2 = threading.Event()
    with split_robot(1, event2) as robot:
        early = run_real(v2_project(), robot.port, [("Abs", v2_params()), ("Abs", v2_params())], "Abs", 2, event2)
    assert early == [True, False]                    # V2 waited for the real notification


# ------------------------------------------------------------------------- 8.11 socket closed


def test_socket_closed_on_error_path(benches):
    """A robot whose flow is not in the Listen node answers 00,false: both FBs end in error, V1
    (16#70 'Device is not a Cobot') with the socket still open, V2 (16#70) after closing it."""
    settings = emulator.EmulatorSettings(start_in_node=False)
    v1 = benches(V1Bench(settings=settings))
    v1.scan(20)
    assert v1.get("T.Conn.ErrorID") == 0x70
    assert len(v1.robot().connections) == 1
    v2 = benches(V2Bench(connect=False, settings=settings))
    v2.set("T.ConnExecute", True)
    v2.until(lambda: v2.get("T.Conn.Error"), 200)
    v2.scan(20)
    assert v2.get("T.Conn.ErrorID") == 0x70
    assert v2.robot().connections == []


# ------------------------------------------------------------------------- 8.10 connection drop


def reset_robot():
    """OK to the motion, then a TCP reset 0.2 s later (no tag notification)."""
    def responder(frame: bytes, index: int) -> list:
        if frame == CHECK_LISTEN:
            return [LISTEN_OK]
        ident, _ = script_of(frame)
        return [tmsct_reply(f"{ident},OK"), 0.2, RESET]
    return FakeRobot(responder)


def drop_run(project, inst: str, params: dict, version: int) -> dict:
    with reset_robot() as robot:
        vm = project.start(scan="1ms")
        r = Runner(vm, {"Connected": "T.Cobot.Connected", "Error": f"T.{inst}.Error"})
        try:
            vm.set("T.Port", robot.port)
            if version == 1:
                vm.set("T.TimeOut", 100)
            vm.set("T.ConnExecute", True)
            r.run_until(lambda s: s["Connected"], 5000, "connected")
            for key, value in params.items():
                vm.set(f"T.{inst}Param.{key}", value)
            vm.set(f"T.{inst}Execute", True)
            r.run_until(lambda s: s["Error"], 10_000_000, "error", timeout_s=10)   # wall-time bound (the robot waits 0.2 s)
            r.run_for(3000)
            return {"WaitingReturn": vm.get("T.Cobot.WaitingReturn"), "Connected": vm.get("T.Cobot.Connected"),
                    "MoveErrorID": vm.get(f"T.{inst}.ErrorID"), "ConnErrorID": vm.get("T.Conn.ErrorID")}
        finally:
            vm.close()


def test_waiting_return_cleared_when_the_connection_drops():
    v1 = drop_run(harness_project(), "Abs", v1_params(), 1)
    assert v1["WaitingReturn"] and v1["Connected"]             # V1: never notices the RST (8.10)
    assert v1["MoveErrorID"] == 0x100                           # 'TCP receive error' in step 100
    v2 = drop_run(v2_project(), "Abs", v2_params(), 2)
    assert not v2["WaitingReturn"] and not v2["Connected"]
    assert v2["MoveErrorID"] == 0x99 and v2["ConnErrorID"] == 0x90


# ------------------------------------------------------------------------- port as UINT


def test_port_above_32767():
    """The same scenario (a robot on port 40000+, the HMI globals of Table 6.2.1) on both projects:
    V1's Connect_Dest_PortIP is an INT and cannot hold the port; V2's is a UINT and connects."""
    from stvm.scenario import ScenarioDriver, ScenarioError, parse_scenario
    port = free_high_port()
    server = emulator.start_server(host="127.0.0.1", port=port)
    try:
        scenario = parse_scenario({"set": {"Connect_AddressIP": "127.0.0.1", "Connect_Dest_PortIP": port,
                                           "Connect_Execute": True}}, "port-scenario")
        v1 = stvm.load([str(ST_SRC / "PnP_Example.st")]).start(scan="1ms")
        with pytest.raises(ScenarioError, match="out of range for INT"):
            ScenarioDriver(scenario, v1).apply_initial()
        v1.close()
        v2 = load_library(V2).start(scan="1ms")
        try:
            ScenarioDriver(scenario, v2).apply_initial()
            r = Runner(v2, {"Connected": "Cobot.Connected"})
            r.run_until(lambda s: s["Connected"], 5000, "V2 connected")
            assert v2.get("PnP_Example_Instance.Connect.Connected")
        finally:
            v2.close()
    finally:
        server.stop()


# ------------------------------------------------------------------------- MoveCircle speed range


def circle(version: int) -> dict:
    p = {"DataFormat": "CAP_Circle", "Speed": 200, "AccelTime": 200, "ArcAngle": 0}
    if version == 1:
        p["CommandID"] = 2
    p.update({f"ArcPoint.{k}": v for k, v in zip(("X", "Y", "Z", "RX", "RY", "RZ"), (437.0, -102.0, 361.0, 180.0, 0.0, 90.0))})
    p.update({f"EndPoint.{k}": v for k, v in zip(("X", "Y", "Z", "RX", "RY", "RZ"), (457.0, -122.0, 361.0, 180.0, 0.0, 90.0))})
    return p


def test_move_circle_speed_range(benches):
    v1 = benches(V1Bench())
    end = v1.move("Circ", circle(1))
    assert end["Error"] and end["ErrorID"] == 0x26 and len(v1.rx()) == 1     # refused, never sent
    v2 = benches(V2Bench("Circ"))
    v2.start("Circ", circle(2))
    assert v2.finish("Circ")["Done"]
    assert v2.pose()[:2] == pytest.approx([457.0, -122.0], abs=1e-3)


# ------------------------------------------------------------------------- PrecisePositioning


def test_precise_positioning_not_inverted(benches):
    """With PrecisePositioning TRUE V1 sends disablePrecise=true: the robot skips its settle time
    (emulator precise_settle_ms) -- the motion is *not* positioned precisely."""
    settings = emulator.EmulatorSettings(precise_settle_ms=400)
    v1 = benches(V1Bench(settings=settings))
    start = v1.vm.scan_count
    assert v1.move("Abs", v1_params(precise=True))["Done"]
    v1_scans = v1.vm.scan_count - start
    v2 = benches(V2Bench("Abs", settings=settings))
    start = v2.vm.scan_count
    v2.start("Abs", v2_params(precise=True))
    assert v2.finish("Abs")["Done"]
    v2_scans = v2.vm.scan_count - start
    assert script_of(v1.rx()[1])[1].split("\r\n")[0].endswith(",true)")
    assert script_of(v2.rx()[1])[1].split("\r\n")[0].endswith(",false)")
    assert v2_scans - v1_scans == pytest.approx(400, abs=25)    # the settle time; V1's steps differ a little


# ------------------------------------------------------------------------- Pause(), 8.12


def test_pause_reaches_the_robot(benches):
    """V1's Pause() frame always has a one-digit checksum; the robot answers CPERR 01 and V1 is Done
    anyway (it does not read the reply, 8.12): the robot keeps moving. V2 pauses it."""
    v1 = benches(V1Bench())
    v1.set_many("T.AbsParam", v1_params(target=(417.0, -122.0, 250.0, 180.0, 0.0, 90.0), speed=20))
    v1.set("T.AbsExecute", True)
    v1.scan(100)
    assert v1.move("Prg", {"CommandID": 5, "Command": "Pause"}, 2000)["Done"]
    v1.scan(20)
    assert tm_frame("CPERR", "01") in v1.tx() and not v1.robot().paused
    v2 = benches(V2Bench("Abs", "Prg"))
    v2.start("Abs", v2_params(target=(417.0, -122.0, 250.0, 180.0, 0.0, 90.0), speed=20))
    v2.scan(100)
    v2.start("Prg", {"Command": "Pause"})
    assert v2.finish("Prg")["Done"] and v2.robot().paused
