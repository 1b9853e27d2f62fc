"""Shared machinery of the robot-library tests (tests/cbt_v2, tests/rockwell, tests/kuka, tests/schneider, tests/cell).

The libraries under ``st_src/<folder>/`` are ST only; the tests load them with stvm, add a small
harness PROGRAM of their own where an FB is exercised alone, and run them against the TM emulator:

* in lockstep (:class:`Cell`): VM and emulated robots in one process on the VM's virtual clock,
  no sockets, bit-identical runs; one or several robots (``LockstepTransport.add_robot``);
* over loopback with real sockets where a scripted robot is needed (``thesis_harness.FakeRobot``,
  reused from the thesis tests).

Expected frames are computed here from ``shared/spec/tm_protocol.md`` section 2 (two-digit
checksum, LENGTH in bytes), independently of both the ST code and ``emulator.framing``.
"""

from __future__ import annotations

import re
import sys
import tempfile
import tomllib
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import stvm

REPO = Path(__file__).resolve().parents[1]
ST_SRC = REPO / "st_src"
V2 = ST_SRC / "cbt_v2"
ROCKWELL = ST_SRC / "rockwell"
KUKA = ST_SRC / "kuka"
THESIS_TESTS = Path(__file__).resolve().parent / "thesis"
if str(THESIS_TESTS) not in sys.path:
    sys.path.insert(0, str(THESIS_TESTS))

# the six PnP targets every library's demo drives (the thesis demo's, st_src/scenarios/pnp_demo.toml)
with (ST_SRC / "scenarios" / "pnp_demo.toml").open("rb") as _fh:
    _DEMO = tomllib.load(_fh)["set"]
PNP_TARGETS = [tuple(_DEMO[f"PnP_MoveParameters[{i}].TargetPosition.{k}"] for k in ("X", "Y", "Z", "RX", "RY", "RZ"))
               for i in range(6)]
PNP_SPEEDS = [_DEMO[f"PnP_MoveParameters[{i}].Speed"] for i in range(6)]
PNP_ACCEL_MS = [_DEMO[f"PnP_MoveParameters[{i}].AccelTime"] for i in range(6)]


# ====================================================================== frames (spec section 2)


def tm_frame(header: str, data: str) -> bytes:
    """tm_protocol.md 2: $HEADER,LEN,DATA,*CS CR LF with LEN in bytes and CS two hex digits."""
    payload = data.encode("utf-8")
    body = header.encode("ascii") + b"," + str(len(payload)).encode("ascii") + b"," + payload + b","
    checksum = 0
    for byte in body:
        checksum ^= byte
    return b"$" + body + b"*" + f"{checksum:02X}".encode("ascii") + b"\r\n"


def script_of(frame: bytes) -> tuple[str, str]:
    """(ID, script) of a $TMSCT frame."""
    first = frame.index(b",")
    second = frame.index(b",", first + 1)
    length = int(frame[first + 1:second])
    data = frame[second + 1:second + 1 + length].decode("utf-8")
    ident, _, script = data.partition(",")
    return ident, script


MOTIONS = ("PTP", "Line", "Circle", "Move_PTP", "Move_Line", "PLine", "Move_PLine")
_CALL = re.compile(r"^(\w+)\((.*)\)$")


def statements(script: str) -> list[tuple[str, list[Any]]]:
    """The calls of a TM script, one per CRLF line: (name, arguments) with numbers as floats,
    strings unquoted, true/false as bools (enough for the scripts the libraries send)."""
    out = []
    for line in script.split("\r\n"):
        match = _CALL.match(line.strip())
        if not match:
            out.append((line.strip(), []))
            continue
        args: list[Any] = []
        for raw in _split_args(match.group(2)):
            raw = raw.strip()
            if raw.startswith('"'):
                args.append(raw.strip('"'))
            elif raw.lower() in ("true", "false"):
                args.append(raw.lower() == "true")
            elif raw:
                try:
                    args.append(float(raw))
                except ValueError:
                    args.append(raw)          # an expression (e.g. GetString(...)): as written
        out.append((match.group(1), args))
    return out


def _split_args(text: str) -> list[str]:
    parts, depth, current = [], 0, ""
    for ch in text:
        if ch in "({":
            depth += 1
        elif ch in ")}":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += ch
    if current:
        parts.append(current)
    return parts


def motion_commands(frames: Iterable[bytes]) -> list[tuple[str, list[Any]]]:
    """Every motion call the PLC sent, in order (IDs, QueueTags and other statements dropped)."""
    out = []
    for frame in frames:
        if frame.startswith(b"$TMSCT"):
            out += [(name, args) for name, args in statements(script_of(frame)[1]) if name in MOTIONS]
    return out


def free_high_port() -> int:
    """A free loopback TCP port above 32767 (which an INT port variable cannot hold)."""
    import random
    import socket
    for port in random.Random().sample(range(32768, 61000), 200):
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
            try:
                probe.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError("no free port above 32767")


# ====================================================================== projects


def manifest_files(folder: Path) -> list[Path]:
    with (folder / "stvm.toml").open("rb") as fh:
        return [folder / name for name in tomllib.load(fh)["project"]["files"]]


_HARNESS_DIR = Path(tempfile.mkdtemp(prefix="stvm-robotlibs-harness-"))


@lru_cache(maxsize=None)
def load_library(folder: Path, harness: str = "", drop: tuple[str, ...] = ()) :
    """The library's manifest files minus `drop` (file names), plus a harness program (ST text)."""
    files = [f for f in manifest_files(folder) if f.name not in drop]
    if harness:
        name = f"harness_{abs(hash((str(folder), harness))):x}.st"
        path = _HARNESS_DIR / name
        path.write_text(harness, encoding="utf-8")
        files.append(path)
    return stvm.load([str(f) for f in files])


# ====================================================================== lockstep runs


class Cell:
    """A fresh VM of `project` in lockstep with emulated robots: robot 0 answers any address, each
    of `robots` ((host, port) pairs) only its own. `settings`/`faults` apply to every robot."""

    def __init__(self, project, scan: str = "1ms", settings=None, faults: Sequence[str] = (),
                 robots: Sequence[tuple[str, int]] = (), latency_scans: int = 1) -> None:
        import emulator
        from stvm.lockstep import LockstepTransport
        settings = settings or emulator.EmulatorSettings()
        plan = emulator.parse_faults(list(faults))
        self.transport = LockstepTransport(latency_scans=latency_scans, settings=settings, faults=plan)
        for host, port in robots:
            self.transport.add_robot(host, port, settings=settings, faults=plan)
        self.vm = project.start(scan=scan, transport=self.transport)
        self.transport.attach(self.vm)
        self.samples: list[dict[str, Any]] = []
        self.watch: dict[str, str] = {}

    # ---- driving
    def set(self, path: str, value: Any) -> None:
        self.vm.set(path, value)

    def set_many(self, prefix: str, values: dict[str, Any]) -> None:
        for key, value in values.items():
            self.vm.set(f"{prefix}.{key}", value)

    def get(self, path: str) -> Any:
        """The value of `path`; STRING values as str (the VM holds them as bytes)."""
        value = self.vm.get(path)
        return value.decode("latin-1") if isinstance(value, bytes) else value

    def scan(self, n: int = 1) -> None:
        for _ in range(n):
            self.vm.scan()
            if self.watch:
                self.samples.append({k: self.get(p) for k, p in self.watch.items()} | {"scan": self.vm.scan_count - 1})

    def until(self, predicate: Callable[[], bool], max_scans: int = 30000, what: str = "condition") -> int:
        """Scan until `predicate()`; returns the number of scans run. Fails after `max_scans`."""
        for i in range(max_scans):
            self.scan()
            if predicate():
                return i + 1
        raise AssertionError(f"{what} not reached within {max_scans} scans")

    # ---- robot side
    def robot(self, index: int = 0):
        return self.transport.robots[index].robot

    def frames(self, direction: str, robot: int = 0) -> list[bytes]:
        return [f.data for f in self.transport.frames if f.direction == direction and f.robot == robot]

    def rx(self, robot: int = 0) -> list[bytes]:
        """Frames the PLC sent to robot `robot`, byte for byte."""
        return self.frames("rx", robot)

    def tx(self, robot: int = 0) -> list[bytes]:
        return self.frames("tx", robot)

    def pose(self, robot: int = 0) -> list[float]:
        return self.robot(robot).snapshot()["pose"]

    def close(self) -> None:
        self.vm.close()


def states(samples: list[dict], keys: Sequence[str]) -> list[tuple]:
    """Consecutive distinct values of `keys` over the samples (run-length collapsed)."""
    out: list[tuple] = []
    for sample in samples:
        state = tuple(sample[k] for k in keys)
        if not out or out[-1] != state:
            out.append(state)
    return out


# ====================================================================== property tests (issue 31)
#
# Every library FB is driven over its whole input space against the emulator in lockstep: hypothesis
# draws a schedule (steps of input assignments, the FB's Execute/Enable level and a number of
# scans; one mode toggles Execute every scan) and the run asserts, after every scan, that the
# controller did not fault (stvm's RuntimeFault ends the scan: on a real PLC a major fault),
# that every error output is one of the seed's documented codes, and that Done and Error are
# never TRUE together. The CI tests run a bounded, derandomized number of examples; the bench
# (bench/bench_robotlibs_props.py) the same properties with many more.

import math as _math

INT_RANGES = {"SINT": (-128, 127), "INT": (-32768, 32767), "DINT": (-2147483648, 2147483647),
              "USINT": (0, 255), "UINT": (0, 65535), "UDINT": (0, 4294967295), "WORD": (0, 65535)}
REAL_EXTREMES = (0.0, -1.0, 1.0, _math.nan, _math.inf, -_math.inf, 3.4028234e38, -3.4028234e38, 1.0e-45)


def value_strategy(kind):
    """Values of an input of `kind`: an elementary type name, 'STRING[n]', or a tuple of the
    allowed values (an enumeration); the type's extremes are drawn often."""
    from hypothesis import strategies as st
    if isinstance(kind, tuple):
        return st.sampled_from(kind)
    if kind == "BOOL":
        return st.booleans()
    if kind in INT_RANGES:
        low, high = INT_RANGES[kind]
        edges = sorted({0, 1, low, high} | ({-1} if low < 0 else set()))
        return st.one_of(st.sampled_from(edges), st.integers(low, high), st.integers(max(low, -200), min(high, 200)))
    if kind in ("REAL", "LREAL"):
        return st.one_of(st.sampled_from(REAL_EXTREMES), st.floats(-2000.0, 2000.0, width=32))
    if kind.startswith("STRING["):
        size = int(kind[7:-1])
        return st.one_of(st.sampled_from(["", "x" * size]), st.text(st.characters(min_codepoint=32, max_codepoint=126),
                                                                         max_size=size))
    raise ValueError(kind)


def schedules(inputs: dict[str, Any], max_steps: int = 6, max_scans: int = 60):
    """Lists of steps (assignments, execute level, scans); `inputs` maps a variable path to its kind.
    A step with scans < 0 toggles Execute every scan for -scans scans."""
    from hypothesis import strategies as st
    names = sorted(inputs)
    assignment = st.dictionaries(st.sampled_from(names), st.nothing(), max_size=0) if not names else \
        st.lists(st.sampled_from(names), max_size=6, unique=True).flatmap(
            lambda chosen: st.fixed_dictionaries({n: value_strategy(inputs[n]) for n in chosen}))
    step = st.tuples(assignment, st.booleans(), st.one_of(st.integers(1, max_scans), st.integers(-20, -2)))
    return st.lists(step, min_size=1, max_size=max_steps)


class Probe:
    """One FB's outputs: its Done and Error (paths; None when it has none), its error code path and
    the codes its seed documents (`decode` maps the raw value first)."""

    def __init__(self, name: str, done: str | None, error: str | None, code: str, codes: Iterable[int],
                 error_when: Callable[[Any], bool] | None = None) -> None:
        self.name, self.done, self.error, self.code, self.codes = name, done, error, code, frozenset(codes)
        self.error_when = error_when
        self.seen: set[int] = set()

    def check(self, cell: Cell, where: str) -> None:
        done = bool(cell.get(self.done)) if self.done else False
        code = cell.get(self.code)
        error = bool(cell.get(self.error)) if self.error else bool(self.error_when and self.error_when(cell))
        assert not (done and error), f"{self.name}: Done and Error both TRUE ({where})"
        if error:
            self.seen.add(code)
            assert code in self.codes, f"{self.name}: error code {code} is not one the seed documents ({where})"


def run_schedule(cell: Cell, steps, execute: str, probes: Sequence[Probe]) -> int:
    """Play `steps` on `cell`; returns the scans run. A runtime fault fails with the step that caused it."""
    from stvm.runtime.vm import RuntimeFault
    scans = 0
    for index, (assignments, level, n) in enumerate(steps):
        for path, value in assignments.items():
            cell.set(path, value)
        for k in range(abs(n)):
            cell.set(execute, level if n > 0 else (level ^ (k % 2 == 1)))
            where = f"step {index} {assignments!r}, scan {k}"
            try:
                cell.vm.scan()
            except RuntimeFault as fault:
                raise AssertionError(f"runtime fault at {where}: {fault}") from None
            scans += 1
            for probe in probes:
                probe.check(cell, where)
    return scans


# the ErrorIDs of CBT_Commands: the thesis's (V1, 16#10..16#110, thesis section 5.3 tables) and the
# ones V2 adds and documents in its file headers (st_src/cbt_v2/*.st)
V1_ERROR_IDS = frozenset([0x10, 0x11, 0x15, 0x20, 0x21, 0x25, 0x26, 0x27, 0x28, 0x29, 0x30, 0x31, 0x32, 0x35, 0x36,
                          0x40, 0x50, 0x60, 0x70, 0x80, 0x90, 0x99, 0x100, 0x110])
V2_ERROR_IDS = V1_ERROR_IDS | frozenset([0x12, 0x16, 0x17, 0x2A, 0x2B, 0x2C, 0x2D, 0x2E, 0x71, 0x72, 0x81, 0x120])


# ====================================================================== the per-seed tables (docs/robotlibs_<vendor>.md)


def seed_table(doc: Path) -> dict[str, tuple[str, str, str]]:
    """The rows `| item | status | how / why | tests |` of a docs/robotlibs_<vendor>.md table, by item."""
    rows = {}
    for line in doc.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and line.startswith("|") and cells[1] in ("implemented", "substituted", "refused"):
            rows[cells[0].strip("`")] = (cells[1], cells[2], cells[3])
    return rows


def check_seed_table(doc: Path, items: Iterable[str], test_files: Sequence[Path],
                     spellings: Callable[[str], Sequence[str]] = lambda item: (item,)) -> None:
    """Every seed item is in the table; an implemented or substituted one names tests that exist in
    `test_files` and one of them mentions the item (in one of its `spellings`); a refused one says why
    (and, when it names tests, those exist and produce its refusal)."""
    import ast
    table = seed_table(doc)
    missing = set(items) - set(table)
    assert not missing, f"{doc.name}: seed items not in the table: {sorted(missing)}"
    bodies: dict[str, str] = {}
    for path in test_files:
        source = path.read_text(encoding="utf-8")
        lines = source.splitlines()
        for node in ast.parse(source).body:
            if isinstance(node, ast.FunctionDef) and node.name.startswith("test_"):
                first = min([d.lineno for d in node.decorator_list] + [node.lineno])
                bodies[node.name] = "\n".join(lines[first - 1:node.end_lineno])
    for item, (status, why, tests) in table.items():
        names = re.findall(r"test_\w+", tests)
        for name in names:
            assert name in bodies, f"{doc.name}: {item}: {name} does not exist"
        if status == "refused":
            assert why, f"{doc.name}: {item} refused without a reason"
        else:
            assert names, f"{doc.name}: {item} ({status}) names no test"
        if names:
            assert any(re.search(rf"(?<![\w#]){re.escape(s)}(?!\w)", bodies[n]) for n in names for s in spellings(item)), \
                f"{doc.name}: {item}: none of {names} mentions it"
