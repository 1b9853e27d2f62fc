"""A recorded run as plain data: signals, initial values, changes, emulator frames, events.

Values are IEC literal text (`format_value`: `TRUE`, `12`, `1.5`, `'text'`, `T#2s`,
`CBT_Commands_Lib\\eCBT_MovCmd_Movement#PTP`), so a trace read back from a file compares exactly
with one just recorded, and a divergence report prints what ST would print. Times are integer
nanoseconds of the VM clock; scan `k` is the `k`-th scan of the run (VM time `k * scan_ns`), its
values are sampled at the end of the scan.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field


@dataclass(frozen=True)
class SignalInfo:
    name: str
    type: str      # IEC type text: BOOL, INT, REAL, STRING[50], TIME, an enum's qualified name
    kind: str      # bool, int, real, time, string, enum ("?" when unknown, e.g. read from CSV)
    bits: int = 0  # integers: width; REAL 32 / LREAL 64


@dataclass(frozen=True)
class FrameEntry:
    """A Listen Node frame the emulated robot received ("rx") or sent ("tx")."""

    scan: int      # the scan after which the emulator handled it (its time is in that scan's window)
    t_ns: int
    direction: str
    conn: int
    data: str      # the frame bytes, decoded as latin-1 (byte-exact)

    def text(self) -> str:
        return f"{self.direction}#{self.conn} {escape_frame(self.data)}"


@dataclass(frozen=True)
class EventEntry:
    """Something that happened to the run, not in the ST variables: a scenario event, an
    injected fault, a runtime fault."""

    scan: int
    text: str


@dataclass
class Trace:
    signals: list[SignalInfo]
    scan_ns: int
    scans: int                                   # number of scans recorded (0 … scans-1)
    initial: list[str]                           # values at the end of scan 0, one per signal
    changes: list[tuple[int, int, str]] = field(default_factory=list)  # (scan ≥ 1, signal index, value)
    frames: list[FrameEntry] = field(default_factory=list)
    events: list[EventEntry] = field(default_factory=list)
    meta: dict = field(default_factory=dict)     # informative only; never compared
    _series: dict | None = field(default=None, repr=False, compare=False)

    def index_of(self, name: str) -> int:
        lowered = name.lower()
        for i, signal in enumerate(self.signals):
            if signal.name.lower() == lowered:
                return i
        raise KeyError(name)

    def series(self, index: int) -> tuple[list[int], list[str]]:
        """(scans, values) where signal `index` takes a new value; scans[0] is 0."""
        if self._series is None:
            table: dict[int, tuple[list[int], list[str]]] = {
                i: ([0], [value]) for i, value in enumerate(self.initial)}
            for scan, i, value in self.changes:
                scans, values = table[i]
                scans.append(scan)
                values.append(value)
            self._series = table
        return self._series[index]

    def value_at(self, index: int, scan: int) -> str:
        scans, values = self.series(index)
        return values[bisect.bisect_right(scans, scan) - 1]

    def last_change(self, index: int, scan: int) -> int:
        """The scan ≤ `scan` in which signal `index` last took its value then."""
        scans, _ = self.series(index)
        return scans[bisect.bisect_right(scans, scan) - 1]

    def changes_in(self, scan: int) -> list[tuple[int, str]]:
        lo = bisect.bisect_left(self.changes, (scan, -1, ""))
        out = []
        for s, i, value in self.changes[lo:]:
            if s != scan:
                break
            out.append((i, value))
        return out

    def time_of(self, scan: int) -> int:
        return scan * self.scan_ns


_FRAME_ESCAPES = {"\r": "$R", "\n": "$L", "\t": "$T", "$": "$$"}


def escape_frame(data: str) -> str:
    """Frame text on one line, with ST string escapes for CR, LF, TAB, `$` and other controls."""
    out = []
    for ch in data:
        if ch in _FRAME_ESCAPES:
            out.append(_FRAME_ESCAPES[ch])
        elif ord(ch) < 32 or ord(ch) >= 127:
            out.append(f"${ord(ch):02X}")
        else:
            out.append(ch)
    return "".join(out)


def unescape_frame(text: str) -> str:
    out = []
    i = 0
    simple = {"R": "\r", "L": "\n", "T": "\t", "$": "$", "N": "\n"}
    while i < len(text):
        ch = text[i]
        if ch == "$" and i + 1 < len(text):
            nxt = text[i + 1].upper()
            if nxt in simple:
                out.append(simple[nxt])
                i += 2
                continue
            out.append(chr(int(text[i + 1:i + 3], 16)))
            i += 3
            continue
        out.append(ch)
        i += 1
    return "".join(out)
