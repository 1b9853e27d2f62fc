"""Shared machinery for the thesis FB tests (tests/thesis/test_fb_*.py, test_pnp.py).

What is here, and why it is written from the specs rather than imported:

* **Expected frames** (`tm_checksum`, `thesis_frame`, `rtfs0`): the TM Listen Node framing of
  ``shared/spec/tm_protocol.md`` section 2 and Sysmac ``RealToFormatString`` /
  ``BYTE_TO_STRING`` of ``shared/spec/sysmac.md`` section 6, re-implemented in a few lines so that
  the bytes the thesis FBs send (running on stvm) are compared with bytes computed independently
  of both stvm and ``emulator.framing``.
* **A harness program** (`HARNESS_ST`): one PROGRAM ``T`` with one instance of each of the seven
  thesis FBs (from ``st_src/``, unchanged) wired to one ``stCBT_Connection`` like the ladder
  rungs of section 5.4, all pins reachable as ``T.<inst>.<pin>``.  Loaded once per session.
* **Robots**: the bundled TM emulator over loopback (`Emulator`, frames captured with its JSON
  log) and `FakeRobot`, a plain socket server of our own with scripted replies, for the cases
  the emulator cannot produce deterministically (reply timing, stale bytes, RST, silence); it
  captures the raw byte stream the PLC sends.
* **Per-scan traces** (`Runner`): every scan samples Busy/Done/Error/ErrorID/CmdID_Ack (and the
  internal FB_step), so tests assert on the sequence of states and on scan distances the FB code
  guarantees, never on absolute scan numbers that depend on wall-clock timing.

Timing model: the VM runs on its virtual clock (each scan = 1 ms of VM time, as fast as the
CPU allows: ~3 VM ms per wall ms here) while the robot runs on the wall clock; `Runner` yields
the GIL every few scans so the socket server threads run.  Timers (TON in CBT_Connect and
PnP_Example) therefore count VM time exactly, and their scan distances are asserted exactly;
robot round trips are asserted only in order.  Motions are kept >= ~80 ms of wall time: a motion
that ends before the FB's step 90 clears the receive buffer loses its tag (see
FIDELITY_FINDINGS.md, "8.5 + step 90's SktClearBuf").
"""

from __future__ import annotations

import contextlib
import decimal
import json
import socket
import struct
import tempfile
import threading
import time
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Iterable

import stvm
from stvm.settings import SysmacSettings

REPO = Path(__file__).resolve().parents[2]
ST_SRC = REPO / "st_src"

# ====================================================================== expected frames (specs)


def tm_checksum(body: bytes) -> int:
    """tm_protocol.md §2: XOR of every byte after '$' up to and including the ',' before '*'."""
    value = 0
    for byte in body:
        value ^= byte
    return value


def byte_to_string(value: int) -> str:
    """sysmac.md §6 BYTE_TO_STRING, default `hex_nopad`: upper-case hex without leading zero."""
    return format(value & 0xFF, "X")


def tm_frame(header: str, data: str, checksum_text: Callable[[int], str] | None = None) -> bytes:
    """A frame as tm_protocol.md §2 defines it (decimal LENGTH in bytes, 2-digit checksum).
    `checksum_text` renders the checksum differently (the thesis: `byte_to_string`)."""
    payload = data.encode("utf-8")
    body = header.encode("ascii") + b"," + str(len(payload)).encode("ascii") + b"," + payload + b","
    cs = tm_checksum(body)
    text = checksum_text(cs) if checksum_text else format(cs, "02X")
    return b"$" + body + b"*" + text.encode("ascii") + b"\r\n"


def thesis_frame(cmd_id: int | str, script: str) -> bytes:
    """What the thesis FBs build in steps 40/50 (Annex A2 l.4984-5010): header TMSCT, LENGTH =
    LEN(id ',' script), checksum = XOR over 'TMSCT,len,id,script,' (sysmac.md 8.1: under the
    default `text_nul` the loop's extra byte is the 16#00 terminator, so this is the right XOR),
    rendered with BYTE_TO_STRING -> one digit below 16#10 (sysmac.md 8.2)."""
    return tm_frame("TMSCT", f"{cmd_id},{script}", byte_to_string)


def frame_checksum(frame: bytes) -> int:
    """The XOR of a frame's body (for choosing parameter sets with a one-digit checksum)."""
    return tm_checksum(frame[1:frame.rindex(b",*") + 1])


def rtfs0(value: float) -> str:
    """sysmac.md §6 RealToFormatString(In, Exponent:=FALSE, Sign:=TRUE, MinLen:=1, DecPlace:=0) —
    the thesis's coordinate formatting (sysmac.md 8.13): the exact float32 value, rounded to a
    whole number half away from zero, '+' for >= 0 and '-' for < 0 even when it rounds to 0."""
    f32 = struct.unpack("<f", struct.pack("<f", value))[0]
    exact = decimal.Decimal(f32)                      # the float32's exact binary value
    with decimal.localcontext() as ctx:
        ctx.prec = 400
        whole = exact.quantize(decimal.Decimal(1), rounding=decimal.ROUND_HALF_UP)  # half away from 0
    sign = "-" if f32 < 0 else "+"
    return f"{sign}{abs(int(whole))}"


def pose_text(values: Iterable[float]) -> str:
    return ",".join(rtfs0(v) for v in values)


def tmsta_reply(data: str) -> bytes:
    return tm_frame("TMSTA", data)


def tmsct_reply(data: str) -> bytes:
    return tm_frame("TMSCT", data)


def cperr_reply(code: str) -> bytes:
    return tm_frame("CPERR", code)


LISTEN_OK = tmsta_reply("00,true,Listen1")            # tm_protocol.md §5.1 ($TMSTA,15,00,true,Listen1,*79)
CHECK_LISTEN = b"$TMSTA,2,00,*41\r\n"                 # thesis l.4369 / tm_protocol.md §5.1, verbatim


def tag_notification(tag: int) -> bytes:
    """tm_protocol.md §5.3: unsolicited `01,<nn>,true`, nn zero-padded to 2 digits."""
    return tmsta_reply(f"01,{tag:02d},true")


# ====================================================================== the ST harness

FB_FILES = ["CBT_Commands_Lib_Types.st", "CBT_Connect.st", "CBT_MoveAbsolute.st",
            "CBT_MoveRelative.st", "CBT_MoveCircle.st", "CBT_ChangeBase.st", "CBT_ChangeTCP.st",
            "CBT_ProgramControl.st"]

HARNESS_ST = r"""
(* Test harness (tests/thesis): one instance of each thesis FB, all on one connection, as the
   ladder rungs of section 5.4 wire them (CBT := the same stCBT_Connection). Not thesis code. *)
PROGRAM T
VAR
    Cobot : CBT_Commands_Lib\stCBT_Connection;
    Conn : CBT_Commands_Lib\CBT_Connect;
    ConnExecute : BOOL;
    IP : STRING[50] := '127.0.0.1';
    Port : UINT;
    TimeOut : UINT := 100;
    Abs : CBT_Commands_Lib\CBT_MoveAbsolute;
    AbsExecute : BOOL;
    AbsParam : CBT_Commands_Lib\stCBT_MovAbsParam;
    Rel : CBT_Commands_Lib\CBT_MoveRelative;
    RelExecute : BOOL;
    RelParam : CBT_Commands_Lib\stCBT_MovRelParam;
    Circ : CBT_Commands_Lib\CBT_MoveCircle;
    CircExecute : BOOL;
    CircParam : CBT_Commands_Lib\stCBT_MovCircleParam;
    Base : CBT_Commands_Lib\CBT_ChangeBase;
    BaseExecute : BOOL;
    BaseParam : CBT_Commands_Lib\stCBT_BaseParam;
    Tcp : CBT_Commands_Lib\CBT_ChangeTCP;
    TcpExecute : BOOL;
    TcpParam : CBT_Commands_Lib\stCBT_TCParam;
    Prg : CBT_Commands_Lib\CBT_ProgramControl;
    PrgExecute : BOOL;
    PrgParam : CBT_Commands_Lib\stCBT_PrgControl;
END_VAR
Conn(CBT:=Cobot, Execute:=ConnExecute, IPAddress:=IP, IPPort:=Port, Time_Out:=TimeOut);
Abs(CBT:=Cobot, Execute:=AbsExecute, Parameters:=AbsParam);
Rel(CBT:=Cobot, Execute:=RelExecute, Parameters:=RelParam);
Circ(CBT:=Cobot, Execute:=CircExecute, Parameters:=CircParam);
Base(CBT:=Cobot, Execute:=BaseExecute, Parameters:=BaseParam);
Tcp(CBT:=Cobot, Execute:=TcpExecute, Parameters:=TcpParam);
Prg(CBT:=Cobot, Execute:=PrgExecute, Parameters:=PrgParam);
END_PROGRAM
"""

#: instance name -> its Execute and Parameters variables in T
FB_PINS = {
    "Abs": ("AbsExecute", "AbsParam"),
    "Rel": ("RelExecute", "RelParam"),
    "Circ": ("CircExecute", "CircParam"),
    "Base": ("BaseExecute", "BaseParam"),
    "Tcp": ("TcpExecute", "TcpParam"),
    "Prg": ("PrgExecute", "PrgParam"),
}


@lru_cache(maxsize=None)
def harness_project():
    """The seven st_src FBs + the harness program, loaded once per session."""
    folder = Path(tempfile.mkdtemp(prefix="stvm-thesis-harness-"))
    harness = folder / "Harness.st"
    harness.write_text(HARNESS_ST, encoding="utf-8")
    # several files: no manifest applies, so the thesis's dialect is named here (st_src/stvm.toml's)
    return stvm.load([str(ST_SRC / name) for name in FB_FILES] + [str(harness)],
                     settings=SysmacSettings(dialect="sysmac"))


@lru_cache(maxsize=None)
def thesis_project():
    """The whole thesis project as `stvm run st_src/PnP_Example.st` loads it (st_src/stvm.toml)."""
    return stvm.load([str(ST_SRC / "PnP_Example.st")])


def free_port() -> int:
    """A free loopback port <= 32767 (the thesis port global is an INT, Table 6.2.1)."""
    import random
    from stvm.demo import free_loopback_port
    return free_loopback_port(preferred=random.randrange(20000, 32768))


# ====================================================================== per-scan traces

OUTPUTS = ("Busy", "Done", "Error", "ErrorID")

# (Busy, Done, Error, ErrorID) runs of an FB whose Execute fell while Busy: the request still
# completes, and Done shows for exactly one scan (spec section 4, rule 4)
DROPPED_WHILE_BUSY = [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0),
                      (False, False, False, 0)]


def not_connected_states(error_scans: int) -> list[tuple]:
    """Per-scan outputs of an FB executed with no connection: reset, Busy, then 16#99 each scan."""
    return [(False, False, False, 0), (True, False, False, 0)] + [(False, False, True, 0x99)] * error_scans


def assert_done_once_after_drop(runner, start: int) -> None:
    runs = runner.runs(OUTPUTS, start)
    assert [state for state, _, _ in runs] == DROPPED_WHILE_BUSY
    assert runs[2][2] == 1


def move_script_tail(p: dict) -> str:
    """What the move FBs append to the motion (Annex A2-A4): the QueueTag of the command unless
    blending, and ScriptExit() when leaving the node; lines joined by CR LF."""
    tail = "" if p["BlendingEnable"] else f'\r\nQueueTag({p["CommandID"]},0)'
    return tail + ("\r\nScriptExit()" if p.get("ExitNode") else "")


@dataclass
class Sample:
    scan: int
    now_ms: float
    values: dict[str, Any]

    def __getitem__(self, key: str) -> Any:
        return self.values[key]


# The default bound of `Runner.run_until`: in effect the wall-clock timeout alone. The emulator's
# motions take wall-clock time while the VM's clock is virtual, so how many scans a motion spans
# depends on how fast this machine scans (a faster VM needs more of them), not on the ST; a test
# that asserts a scan count passes its own `max_scans`. (20,000 was too few once a scan took
# ~8 µs.) The cap keeps a failing wait's trace to a bounded size.
WALL_BOUND_SCANS = 1_000_000


class Runner:
    """Scans a VM and records, after every scan, the listed variables."""

    def __init__(self, vm, watch: dict[str, str], yield_every: int = 8) -> None:
        self.vm = vm
        self.watch = dict(watch)
        self.yield_every = yield_every
        self.trace: list[Sample] = []
        self._getters: dict[str, tuple[str, Callable[[], Any]]] = {}

    def _getter(self, path: str) -> Callable[[], Any]:
        """A fast reader for `path`: the containers of FB members and struct members are fixed
        objects for the life of the VM, so the path is resolved once."""
        cached = self._getters.get(path)
        if cached is None:
            container, key, _ = self.vm.resolve(path)
            if isinstance(key, int):
                cached = (path, lambda c=container, k=key: c[k])
            else:
                cached = (path, lambda c=container, k=key: getattr(c, k))
            self._getters[path] = cached
        return cached[1]

    def sample(self) -> Sample:
        values = {key: self._getter(path)() for key, path in self.watch.items()}
        return Sample(self.vm.scan_count - 1, self.vm.now_ns / 1e6, values)

    def step(self, n: int = 1) -> Sample:
        for _ in range(n):
            self.vm.scan()
            self.trace.append(self.sample())
            if self.yield_every and self.vm.scan_count % self.yield_every == 0:
                time.sleep(0)   # let the robot's server thread run (the VM clock is virtual)
        return self.trace[-1]

    def run_until(self, predicate: Callable[[Sample], bool], max_scans: int = WALL_BOUND_SCANS,
                  what: str = "condition", timeout_s: float = 20.0) -> Sample:
        """Scan until `predicate` holds, at most `max_scans` scans and `timeout_s` of wall time."""
        deadline = time.monotonic() + timeout_s
        for _ in range(max_scans):
            sample = self.step()
            if predicate(sample):
                return sample
            if time.monotonic() > deadline:
                break
        raise AssertionError(f"{what} not reached after {len(self.trace)} scans; last: {self.trace[-1].values}")

    def run_for(self, scans: int) -> Sample:
        return self.step(scans)

    # ---- trace queries
    def at(self, scan: int) -> Sample:
        return self.trace[scan - self.trace[0].scan]

    def since(self, start: int) -> list[Sample]:
        return [s for s in self.trace if s.scan >= start]

    def output_states(self, start: int) -> list[tuple]:
        """(Busy, Done, Error, ErrorID) of every scan from `start` on."""
        return [tuple(s[k] for k in OUTPUTS) for s in self.since(start)]

    def busy_steps(self, start: int) -> list:
        """The FB_step values the FB went through while Busy, from scan `start` on."""
        out: list = []
        for s in self.since(start):
            if s["Busy"] and (not out or out[-1] != s["FB_step"]):
                out.append(s["FB_step"])
        return out

    def first(self, predicate: Callable[[Sample], bool], start: int = 0) -> Sample:
        for s in self.trace:
            if s.scan >= start and predicate(s):
                return s
        raise AssertionError("no sample matches")

    def states(self, keys: Iterable[str] = OUTPUTS, start: int = 0) -> list[tuple]:
        """The distinct consecutive states of `keys` (run-length collapsed)."""
        out: list[tuple] = []
        for s in self.trace:
            if s.scan < start:
                continue
            state = tuple(s[k] for k in keys)
            if not out or out[-1] != state:
                out.append(state)
        return out

    def runs(self, keys: Iterable[str] = OUTPUTS, start: int = 0) -> list[tuple[tuple, int, int]]:
        """(state, first scan, number of scans) for each run of identical states."""
        keys = tuple(keys)
        out: list[list] = []
        for s in self.trace:
            if s.scan < start:
                continue
            state = tuple(s[k] for k in keys)
            if out and out[-1][0] == state:
                out[-1][2] += 1
            else:
                out.append([state, s.scan, 1])
        return [tuple(x) for x in out]  # type: ignore[misc]


def fb_watch(inst: str, extra: Iterable[str] = (), cmd_ack: bool = True) -> dict[str, str]:
    keys = list(OUTPUTS) + (["CmdID_Ack"] if cmd_ack else []) + ["FB_step", "FB_status"] + list(extra)
    watch = {k: f"T.{inst}.{k}" for k in keys}
    watch["Connected"] = "T.Cobot.Connected"
    watch["WaitingReturn"] = "T.Cobot.WaitingReturn"
    return watch


def set_struct(vm, prefix: str, values: dict[str, Any]) -> None:
    for key, value in values.items():
        vm.set(f"{prefix}.{key}", value)


# ====================================================================== robots


class Emulator:
    """The bundled TM emulator on a loopback port, with its JSON frame log in `log_path`."""

    def __init__(self, log_path: Path, settings=None, faults: Iterable[str] = ()) -> None:
        import emulator
        plan = emulator.parse_faults(list(faults))
        self.log_path = Path(log_path)
        self.server = emulator.start_server(host="127.0.0.1", port=free_port(), log_path=str(log_path),
                                            faults=plan, settings=settings or emulator.EmulatorSettings())
        self.port = self.server.port

    def stop(self) -> None:
        self.server.stop()

    def log(self) -> list[dict]:
        text = self.log_path.read_text(encoding="utf-8") if self.log_path.exists() else ""
        return [json.loads(line) for line in text.splitlines() if line.strip()]

    def frames(self, direction: str) -> list[bytes]:
        """Frames in one direction ('rx' = PLC -> robot, 'tx' = robot -> PLC), as bytes."""
        return [entry["data"].encode("utf-8") for entry in self.log() if entry["dir"] == direction]

    def rx(self) -> list[bytes]:
        return self.frames("rx")

    def tx(self) -> list[bytes]:
        return self.frames("tx")

    def snapshot(self) -> dict:
        return self.server.snapshot()

    def __enter__(self) -> "Emulator":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


def split_client_frames(stream: bytes) -> tuple[list[bytes], bytes]:
    """Length-driven split of the PLC -> robot byte stream (tm_protocol.md §2), tolerant of the
    thesis's one-digit checksums: '$' HEADER ',' LEN ',' DATA(LEN) ',*' 1-2 hex CR LF."""
    frames: list[bytes] = []
    pos = 0
    while True:
        start = stream.find(b"$", pos)
        if start < 0:
            return frames, b""
        c1 = stream.find(b",", start)
        c2 = stream.find(b",", c1 + 1) if c1 >= 0 else -1
        if c2 < 0:
            return frames, stream[start:]
        try:
            length = int(stream[c1 + 1:c2])
        except ValueError:
            pos = start + 1
            continue
        data_end = c2 + 1 + length
        end = stream.find(b"\r\n", data_end)
        if end < 0:
            return frames, stream[start:]
        frames.append(stream[start:end + 2])
        pos = end + 2


CLOSE = "close"   # FakeRobot action: FIN
RESET = "reset"   # FakeRobot action: RST (SO_LINGER 0)


class FakeRobot:
    """A plain TCP server of our own: records every byte the PLC sends and answers each frame
    with what `responder(frame, index)` returns (a list of bytes / CLOSE / RESET; default: the
    Listen-node status reply to TMSTA 00, nothing else).  `push()` sends unsolicited bytes."""

    def __init__(self, responder: Callable[[bytes, int], list] | None = None, backlog: int = 4,
                 accept: bool = True) -> None:
        self.responder = responder or (lambda frame, i: [LISTEN_OK] if frame == CHECK_LISTEN else [])
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind(("127.0.0.1", free_port()))
        self.listener.listen(backlog)
        self.port = self.listener.getsockname()[1]
        self.received = bytearray()
        self.frames: list[bytes] = []
        self.connections = 0
        self._conn: socket.socket | None = None
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread = None
        if accept:
            self._thread = threading.Thread(target=self._serve, daemon=True)
            self._thread.start()

    def _serve(self) -> None:
        self.listener.settimeout(0.05)
        while not self._stop.is_set():
            try:
                conn, _ = self.listener.accept()
            except (socket.timeout, OSError):
                continue
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn.settimeout(0.05)
            with self._lock:
                self.connections += 1
                self._conn = conn
            self._serve_conn(conn)

    def _serve_conn(self, conn: socket.socket) -> None:
        pending = b""
        while not self._stop.is_set():
            try:
                chunk = conn.recv(65536)
            except socket.timeout:
                continue
            except OSError:
                return
            if not chunk:
                return
            with self._lock:
                self.received += chunk
            frames, pending = split_client_frames(pending + chunk)
            for frame in frames:
                with self._lock:
                    index = len(self.frames)
                    self.frames.append(frame)
                for action in self.responder(frame, index):
                    if not self._act(conn, action):
                        return

    def _act(self, conn: socket.socket, action) -> bool:
        try:
            if action == CLOSE:
                conn.shutdown(socket.SHUT_WR)
                return True
            if action == RESET:
                conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
                conn.close()
                return False
            if isinstance(action, (int, float)):
                time.sleep(action)
                return True
            conn.sendall(action)
            return True
        except OSError:
            return False

    def push(self, data) -> None:
        with self._lock:
            conn = self._conn
        if conn is not None:
            self._act(conn, data)
            if data in (CLOSE, RESET):
                # the server thread may sit in recv() on this socket: the kernel sends the
                # FIN/RST once that call returns (<= 50 ms); wait for it
                time.sleep(0.1)

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2)
        with contextlib.suppress(OSError):
            self.listener.close()
        if self._conn is not None:
            with contextlib.suppress(OSError):
                self._conn.close()

    def __enter__(self) -> "FakeRobot":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


def closed_port() -> int:
    """A loopback port with nothing listening (connect -> RST -> refused)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.bind(("127.0.0.1", free_port()))
    port = sock.getsockname()[1]
    sock.close()
    return port


@contextlib.contextmanager
def unanswered_port():
    """A loopback port whose SYNs go unanswered: a listener that never accepts, with its accept
    queue already full (Linux drops further SYNs), so a connect stays in SYN_SENT."""
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.bind(("127.0.0.1", free_port()))
    listener.listen(0)
    port = listener.getsockname()[1]
    fillers = []
    try:
        for _ in range(4):
            filler = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            filler.setblocking(False)
            filler.connect_ex(("127.0.0.1", port))
            fillers.append(filler)
        time.sleep(0.05)
        yield port
    finally:
        for filler in fillers:
            filler.close()
        listener.close()


# ====================================================================== scenario helpers


def start_vm(project=None):
    project = project or harness_project()
    return project.start(scan="1ms")


def connect(vm, port: int, time_out: int = 100, runner: Runner | None = None) -> Runner:
    """Run CBT_Connect until Cobot.Connected (Time_Out 100 -> 1.41 s, sysmac.md 8.7)."""
    runner = runner or Runner(vm, {"Connected": "T.Cobot.Connected", "ConnBusy": "T.Conn.Busy",
                                   "ConnError": "T.Conn.Error", "ConnErrorID": "T.Conn.ErrorID"})
    vm.set("T.Port", port)
    vm.set("T.TimeOut", time_out)
    vm.set("T.ConnExecute", True)
    runner.run_until(lambda s: s["Connected"] or s["ConnError"], max_scans=5000, what="Cobot.Connected")
    assert vm.get("T.Cobot.Connected"), f"connect failed: ErrorID {vm.get('T.Conn.ErrorID'):#x}"
    return runner


# home pose of the emulated TM5-700 (docs/emulator.md "Kinematics")
HOME = (417.5, -122.3, 360.9, 180.0, 0.0, 90.0)


# ====================================================================== bench: robot + VM + runner


class Bench:
    """One test setup: a robot (the emulator, a FakeRobot or a bare port), a fresh VM of the
    harness project, CBT_Connect connected (unless `connect=False`), and a Runner watching `inst`."""

    def __init__(self, tmp_path: Path, inst: str | None = None, robot: str = "emulator", settings=None,
                 faults: Iterable[str] = (), responder=None, port: int | None = None,
                 do_connect: bool = True, time_out: int = 100, extra: Iterable[str] = ()) -> None:
        self.emulator: Emulator | None = None
        self.fake: FakeRobot | None = None
        if robot == "emulator":
            self.emulator = Emulator(Path(tmp_path) / f"frames-{id(self)}.jsonl", settings=settings, faults=faults)
            self.port = self.emulator.port
        elif robot == "fake":
            self.fake = FakeRobot(responder)
            self.port = self.fake.port
        else:
            assert port is not None
            self.port = port
        self.vm = start_vm()
        self.inst = inst
        watch = fb_watch(inst, extra=extra, cmd_ack=inst in ("Abs", "Rel", "Circ")) if inst else {}
        watch.update({"ConnBusy": "T.Conn.Busy", "ConnError": "T.Conn.Error", "ConnErrorID": "T.Conn.ErrorID",
                      "Connected": "T.Cobot.Connected", "WaitingReturn": "T.Cobot.WaitingReturn"})
        self.runner = Runner(self.vm, watch)
        if do_connect:
            connect(self.vm, self.port, time_out=time_out, runner=self.runner)
        self.connected_at = len(self.runner.trace)

    # ---- driving
    def params(self, values: dict[str, Any], inst: str | None = None) -> None:
        set_struct(self.vm, f"T.{FB_PINS[inst or self.inst][1]}", values)

    def start_with(self, values: dict[str, Any]) -> int:
        """Set the FB's parameters and raise Execute; returns the scan it starts in."""
        self.params(values)
        return self.execute(True)

    def execute(self, value: bool = True, inst: str | None = None) -> int:
        """Set Execute; returns the scan number of the next scan (the one that sees it)."""
        self.vm.set(f"T.{FB_PINS[inst or self.inst][0]}", value)
        return self.vm.scan_count

    def until(self, predicate, what: str = "condition", max_scans: int = WALL_BOUND_SCANS) -> Sample:
        return self.runner.run_until(predicate, max_scans=max_scans, what=what)

    def until_end(self, max_scans: int = WALL_BOUND_SCANS) -> Sample:
        return self.until(lambda s: s["Done"] or s["Error"], "Done or Error", max_scans)

    def scans(self, n: int) -> Sample:
        return self.runner.run_for(n)

    def get(self, path: str) -> Any:
        return self.vm.get(path if path.startswith("T.") else f"T.{self.inst}.{path}")

    # ---- robot side
    def rx(self) -> list[bytes]:
        """Frames the PLC sent, byte for byte (emulator log or FakeRobot capture)."""
        if self.emulator is not None:
            return self.emulator.rx()
        if self.fake is not None:
            return list(self.fake.frames)
        return []

    def tx(self) -> list[bytes]:
        return self.emulator.tx() if self.emulator is not None else []

    def wait_rx(self, count: int, timeout_s: float = 2.0) -> list[bytes]:
        deadline = time.monotonic() + timeout_s
        while len(self.rx()) < count and time.monotonic() < deadline:
            time.sleep(0.005)
        return self.rx()

    def wait_tx(self, count: int, timeout_s: float = 2.0) -> list[bytes]:
        deadline = time.monotonic() + timeout_s
        while len(self.tx()) < count and time.monotonic() < deadline:
            time.sleep(0.005)
        return self.tx()

    def close(self) -> None:
        try:
            self.vm.close()
        finally:
            if self.emulator is not None:
                self.emulator.stop()
            if self.fake is not None:
                self.fake.stop()


def make_bench_fixture():
    import pytest

    @pytest.fixture
    def bench(tmp_path):
        made: list[Bench] = []

        def make(*args, **kwargs) -> Bench:
            b = Bench(tmp_path, *args, **kwargs)
            made.append(b)
            return b
        yield make
        for b in made:
            b.close()
    return bench
