"""The per-scan recorder: watched values into preallocated numpy blocks, kept as changes only.

Each scan costs one call of a compiled sampler (a tuple of every watched value, walked from the
program instances and the globals object) and one tuple comparison with the previous scan's. Only
a scan whose tuple differs writes a row into the preallocated blocks, one per value group:
integers (BOOL, ANY_INT, TIME/DT, enums) in `int64`, REAL/LREAL in `float64` (exact for REAL's
float32 values), STRING and 64-bit unsigned values in an object array, plus the row's scan number.
When the blocks are full, numpy finds the cells that differ from the row before and keeps only
those (scan, signal, value) triples; the blocks are then reused. Memory therefore grows with the
number of changes, not with the length of the run (a 1-hour run at 1 ms is 3.6 M scans).

The recorder also keeps the emulator's frames (lockstep runs) and events, and `finish()` turns
everything into a `Trace` of IEC literal text.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from stvm.runtime.format import format_value
from stvm.trace.model import EventEntry, FrameEntry, SignalInfo, Trace
from stvm.trace.signals import Signal, make_sampler, type_text

BLOCK_ROWS = 2048


def _group_of(signal: Signal) -> str:
    ty = signal.type
    kind = ty.kind
    if kind == "real":
        return "f"
    if kind == "string":
        return "o"
    if kind == "int" and ty.bits == 64 and not ty.signed:  # type: ignore[attr-defined]
        return "o"   # ULINT/LWORD do not fit int64
    return "i"


_DTYPES = {"i": np.int64, "f": np.float64, "o": object}


class _Group:
    """The signals of one dtype: a slice of the sampled tuple and a preallocated block."""

    def __init__(self, code: str, indices: list[int], start: int, block_rows: int) -> None:
        self.code = code
        self.indices = np.array(indices, dtype=np.int64)   # signal index of each column
        self.start, self.stop = start, start + len(indices)  # slice of the sampled tuple
        self.block = np.empty((block_rows, len(indices)), dtype=_DTYPES[code])
        self.previous: np.ndarray | None = None   # last row of the previous block
        self.found: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []   # (scans, signal idx, values)

    def flush(self, rows: int, scans: np.ndarray) -> None:
        """Keep the cells of rows 0..rows-1 that differ from the row before (`scans` numbers them)."""
        block = self.block[:rows]
        if self.previous is None:
            stacked, row_scans = block, scans[1:rows]   # row 0 is the initial state, kept apart
        else:
            stacked, row_scans = np.concatenate([self.previous[None, :], block]), scans[:rows]
        differ = stacked[1:] != stacked[:-1]
        if self.code == "f":
            differ &= ~(np.isnan(stacked[1:]) & np.isnan(stacked[:-1]))
        rows_changed, cols = np.nonzero(differ)
        if len(rows_changed):
            values = stacked[1:][rows_changed, cols]
            self.found.append((row_scans[rows_changed], self.indices[cols], values.copy()))
        self.previous = block[rows - 1].copy()


class Recorder:
    """Samples `signals` at the end of every scan of `vm` (call `sample` from an on_scan_end hook,
    or let `attach` register it first in the hook list)."""

    def __init__(self, vm, signals: list[Signal], block_rows: int = BLOCK_ROWS) -> None:
        self.vm = vm
        self.signals = signals
        self.block_rows = block_rows
        by_code: dict[str, list[int]] = {}
        for i, signal in enumerate(signals):
            by_code.setdefault(_group_of(signal), []).append(i)
        order: list[int] = []
        self._groups: list[_Group] = []
        for code, indices in by_code.items():
            self._groups.append(_Group(code, indices, len(order), block_rows))
            order += indices
        # one sampler for all signals, grouped by dtype so that each group is a slice
        self._sample = make_sampler([signals[i] for i in order]) if signals else (lambda: ())
        self._scans = np.empty(block_rows, dtype=np.int64)
        self._last: tuple | None = None
        self._row = 0
        self.first_scan: int | None = None
        self.scans = 0
        self.initial: list[Any] = [None] * len(signals)
        self.frames: list[FrameEntry] = []
        self.events: list[EventEntry] = []
        self._finished: Trace | None = None

    def attach(self, transport=None) -> "Recorder":
        """Record from the next scan on: the sampler runs first among the scan-end hooks (it sees
        what the programs left, before a scenario sets inputs for the next scan)."""
        self.vm.on_scan_end.insert(0, self.sample)
        if transport is not None and hasattr(transport, "on_frame"):
            transport.on_frame.append(self.on_frame)
        return self

    def sample(self, vm) -> None:
        values = self._sample()
        if values == self._last:   # the common case: nothing changed, nothing written
            self.scans += 1
            return
        if self.first_scan is None:
            self.first_scan = vm.scan_count
        row = self._row
        self._scans[row] = vm.scan_count - self.first_scan
        for group in self._groups:
            group.block[row] = values[group.start:group.stop]
        self._last = values
        self.scans += 1
        row += 1
        if row == self.block_rows:
            self._flush(row)
            row = 0
        self._row = row

    def _flush(self, rows: int) -> None:
        for group in self._groups:
            if group.previous is None and rows:
                for col, index in enumerate(group.indices):
                    self.initial[index] = group.block[0, col]
            group.flush(rows, self._scans)

    def on_frame(self, record) -> None:
        self.frames.append(FrameEntry(self.vm.scan_count - self._origin(), record.t_ns,
                                      record.direction, record.conn, record.data.decode("latin-1")))

    def event(self, text: str, scan: int | None = None) -> None:
        """Note an event (scenario, fault) at `scan` (default: the scan being recorded)."""
        if scan is None:
            scan = self.vm.scan_count
        self.events.append(EventEntry(scan - self._origin(), text))

    def _origin(self) -> int:
        """The VM scan that is scan 0 of the trace."""
        return self.first_scan if self.first_scan is not None else self.vm.scan_count

    # --- result -----------------------------------------------------------------------------

    def finish(self, meta: dict | None = None) -> Trace:
        """The recorded run as a `Trace` (idempotent; recording stops)."""
        if self._finished is not None:
            return self._finished
        if self._row:
            self._flush(self._row)
            self._row = 0
        layouts = self.vm.layouts
        types = [s.type for s in self.signals]
        infos = [SignalInfo(s.name, type_text(s.type), s.type.kind, getattr(s.type, "bits", 0)) for s in self.signals]
        initial = [format_value(_python(v, ty), ty, layouts) if self.scans else "" for v, ty in zip(self.initial, types)]
        scans_parts, index_parts, value_parts = [], [], []
        for group in self._groups:
            for scans, indices, values in group.found:
                scans_parts.append(scans)
                index_parts.append(indices)
                value_parts.extend(values.tolist() if group.code != "o" else list(values))
        changes: list[tuple[int, int, str]] = []
        if scans_parts:
            all_scans = np.concatenate(scans_parts)
            all_indices = np.concatenate(index_parts)
            order = np.lexsort((all_indices, all_scans))
            cache: dict[tuple[int, Any], str] = {}
            for k in order.tolist():
                index = int(all_indices[k])
                raw = value_parts[k]
                # floats are not cached: -0.0 == 0.0 would share one text
                key = (index, raw) if not isinstance(raw, float) else None
                text = cache.get(key) if key is not None else None
                if text is None:
                    text = format_value(_python(raw, types[index]), types[index], layouts)
                    if key is not None:
                        cache[key] = text
                changes.append((int(all_scans[k]), index, text))
        trace = Trace(signals=infos, scan_ns=self.vm.base_ns, scans=self.scans, initial=initial,
                      changes=changes, frames=list(self.frames),
                      events=sorted(self.events, key=lambda e: e.scan), meta=dict(meta or {}))
        self._finished = trace
        return trace


def _python(value: Any, ty) -> Any:
    """A numpy cell back to the VM's representation for `format_value`."""
    if isinstance(value, np.generic):
        value = value.item()
    kind = ty.kind
    if kind == "bool":
        return bool(value)
    if kind in ("int", "time", "enum"):
        return int(value)
    if kind == "real":
        return float(value)
    return value
