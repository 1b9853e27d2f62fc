"""Golden comparison: the FIRST place where a run leaves its stored trace, and why.

`compare(expected, actual)` walks both traces and returns the earliest `Divergence` (scan, time,
variable, expected, actual) or None. At the same scan a variable wins over an event, and an event
over an emulator frame, because values are what the ST code computed. `render_report` prints it
with the K scans before it (`--context K`).

`locate_writer(spec, actual, divergence)` finds the ST statement that last wrote the diverging
variable. Lockstep runs are deterministic, so it replays the run to the scan in which the actual
value was last changed and executes that one scan under a line tracer (`sys.settrace`, generated
code only): the statement after which the value differs is the writer. Program bodies keep their
scalars in Python locals during a call (stvm/lower caches them), so the tracer reads the frame's
local when one shadows the variable.
"""

from __future__ import annotations

import bisect
import sys
from dataclasses import dataclass, field

from stvm.runtime.format import format_time
from stvm.trace.model import Trace
from stvm.trace.run import trace_session
from stvm.trace.signals import WatchError, select_signals


@dataclass
class Writer:
    """Where the diverging value came from: an ST statement (`span`) or the scenario/initial
    values (`span` None, `note` says which) in scan `scan`."""

    scan: int
    span: object = None
    source_line: str = ""
    note: str = ""

    def describe(self) -> str:
        if self.span is None:
            return f"{self.note} (scan {self.scan})"
        where = f"{self.span.file}:{self.span.line}:{self.span.column}"
        text = f"{where} (scan {self.scan})"
        if self.source_line:
            text += f": {self.source_line.strip()}"
        return text


@dataclass
class Divergence:
    scan: int
    time_ns: int
    variable: str          # a signal name; "emulator frame", "event", "run length", "signals", "scan period"
    expected: str
    actual: str
    kind: str = "value"    # value, frame, event, length, signals, period
    writer: Writer | None = None
    context: list[str] = field(default_factory=list)

    def summary(self) -> str:
        return (f"first divergence at scan {self.scan} (t={format_time(self.time_ns)}): {self.variable}: "
                f"expected {self.expected}, actual {self.actual}")


# --- comparison -------------------------------------------------------------------------------

def compare(expected: Trace, actual: Trace) -> Divergence | None:
    """The earliest difference between two traces, or None when they are equal.

    Compared: the scan period, the recorded signals (by name, case-insensitive), every value at
    every scan, the events, the emulator frames (scan, direction, connection, bytes), the number
    of scans. Not compared: `meta`, frame times within their scan (CSV keeps none).
    """
    if expected.scan_ns and actual.scan_ns and expected.scan_ns != actual.scan_ns:
        return Divergence(0, 0, "scan period", format_time(expected.scan_ns), format_time(actual.scan_ns), "period")
    exp_names = {s.name.lower(): i for i, s in enumerate(expected.signals)}
    act_names = {s.name.lower(): i for i, s in enumerate(actual.signals)}
    for name, i in exp_names.items():
        if name not in act_names:
            return Divergence(0, 0, expected.signals[i].name, expected.value_at(i, 0) if expected.scans else "",
                              "<not recorded>", "signals")
    for name, i in act_names.items():
        if name not in exp_names:
            return Divergence(0, 0, actual.signals[i].name, "<not recorded>",
                              actual.value_at(i, 0) if actual.scans else "", "signals")
    limit = min(expected.scans, actual.scans)
    candidates: list[tuple[int, int, int, Divergence]] = []
    if limit:
        for order, signal in enumerate(expected.signals):
            ei, ai = order, act_names[signal.name.lower()]
            found = _first_value_difference(expected, ei, actual, ai, limit)
            if found is not None:
                scan, exp_value, act_value = found
                candidates.append((scan, 0, order, Divergence(scan, expected.time_of(scan), signal.name,
                                                              exp_value, act_value)))
                limit = scan + 1   # later scans cannot win; keeps the walk short
    exp_events = [(e.scan, e.text) for e in expected.events]
    act_events = [(e.scan, e.text) for e in actual.events]
    found_event = _first_list_difference(exp_events, act_events)
    if found_event is not None:
        scan, exp_text, act_text = found_event
        candidates.append((scan, 1, 0, Divergence(scan, expected.time_of(scan), "event", exp_text, act_text, "event")))
    exp_frames = [(f.scan, f.text()) for f in expected.frames]
    act_frames = [(f.scan, f.text()) for f in actual.frames]
    found_frame = _first_list_difference(exp_frames, act_frames)
    if found_frame is not None:
        scan, exp_text, act_text = found_frame
        candidates.append((scan, 2, 0, Divergence(scan, expected.time_of(scan), "emulator frame",
                                                  exp_text, act_text, "frame")))
    if expected.scans != actual.scans:
        # an event or frame the shorter trace cannot have (its run had ended) is the length's
        # difference, not a divergence at a scan that never ran
        common = min(expected.scans, actual.scans)
        candidates = [c for c in candidates if c[0] < common]
    if candidates:
        return min(candidates, key=lambda c: c[:3])[3]
    if expected.scans != actual.scans:
        scan = min(expected.scans, actual.scans)
        return Divergence(scan, expected.time_of(scan), "run length", f"{expected.scans} scans",
                          f"{actual.scans} scans", "length")
    return None


def _first_value_difference(expected: Trace, ei: int, actual: Trace, ai: int, limit: int):
    exp_scans, exp_values = expected.series(ei)
    act_scans, act_values = actual.series(ai)
    i = j = 0
    exp_value = act_value = None
    # walk the union of change points in order; values hold until the next change
    while True:
        next_exp = exp_scans[i] if i < len(exp_scans) else None
        next_act = act_scans[j] if j < len(act_scans) else None
        if next_exp is None and next_act is None:
            return None
        scan = min(s for s in (next_exp, next_act) if s is not None)
        if scan >= limit:
            return None
        while i < len(exp_scans) and exp_scans[i] == scan:
            exp_value = exp_values[i]
            i += 1
        while j < len(act_scans) and act_scans[j] == scan:
            act_value = act_values[j]
            j += 1
        if exp_value != act_value:
            return scan, exp_value, act_value


def _first_list_difference(expected: list[tuple[int, str]], actual: list[tuple[int, str]]):
    for exp, act in zip(expected, actual):
        if exp != act:
            return min(exp[0], act[0]), _at(exp), _at(act)
    if len(expected) > len(actual):
        extra = expected[len(actual)]
        return extra[0], _at(extra), "<none>"
    if len(actual) > len(expected):
        extra = actual[len(expected)]
        return extra[0], "<none>", _at(extra)
    return None


def _at(item: tuple[int, str]) -> str:
    return f"{item[1]} (scan {item[0]})"


# --- report -----------------------------------------------------------------------------------

def context_rows(expected: Trace, actual: Trace, divergence: Divergence, before: int) -> list[str]:
    """Lines for the `before` scans up to the divergence: the diverging variable in both traces,
    and what else changed (actual run; `≠` marks a change the golden does not have)."""
    if before <= 0:
        return []
    start = max(0, divergence.scan - before)
    exp_index = act_index = None
    if divergence.kind == "value":
        exp_index = expected.index_of(divergence.variable)
        act_index = actual.index_of(divergence.variable)
    rows = [f"  {'scan':>7}  {'time':<12}  " + (f"{divergence.variable} (expected | actual)   " if exp_index is not None else "")
            + "changes in the actual run"]
    names = [s.name for s in actual.signals]
    exp_frames = {(f.scan, f.text()) for f in expected.frames}
    exp_changes = {(s, expected.signals[i].name.lower(), v) for s, i, v in expected.changes}
    for scan in range(start, divergence.scan + 1):
        cells = []
        if exp_index is not None:
            exp_value = expected.value_at(exp_index, scan) if scan < expected.scans else "-"
            act_value = actual.value_at(act_index, scan) if scan < actual.scans else "-"
            mark = " " if exp_value == act_value else "≠"
            cells.append(f"{exp_value} | {act_value} {mark}".ljust(len(divergence.variable) + 24))
        notes = []
        for index, value in actual.changes_in(scan):
            if index == act_index:
                continue
            flag = "" if (scan, names[index].lower(), value) in exp_changes else " ≠"
            notes.append(f"{names[index]}={value}{flag}")
        for event in actual.events:
            if event.scan == scan:
                notes.append(f"[{event.text}]")
        for frame in actual.frames:
            if frame.scan == scan:
                flag = "" if (frame.scan, frame.text()) in exp_frames else " ≠"
                notes.append(f"<{frame.text()}>{flag}")
        rows.append(f"  {scan:>7}  {format_time(actual.time_of(scan)):<12}  " + "".join(cells) + ", ".join(notes))
    return rows


def render_report(divergence: Divergence, expected: Trace | None = None, actual: Trace | None = None,
                  context: int = 0, golden_name: str = "golden") -> str:
    """The first-divergence report the CLI prints and a failing golden test shows."""
    d = divergence
    if d.kind == "length" and expected is not None and actual is not None:
        shorter, longer = ("this run", golden_name) if actual.scans < expected.scans else (golden_name, "this run")
        lines = [f"trace differs from {golden_name}: {shorter} ended after {min(expected.scans, actual.scans)} "
                 f"scan(s), {longer} has {max(expected.scans, actual.scans)}; the first "
                 f"{min(expected.scans, actual.scans)} scan(s) agree"
                 + (f" (run --cycles {expected.scans} to compare them all)" if actual.scans < expected.scans else ""),
                 f"  expected: {d.expected}",
                 f"  actual:   {d.actual}"]
        return "\n".join(lines) + "\n"
    lines = [f"trace differs from {golden_name}: first divergence at scan {d.scan} (t={format_time(d.time_ns)})",
             f"  variable: {d.variable}",
             f"  expected: {d.expected}",
             f"  actual:   {d.actual}"]
    if d.writer is not None:
        lines.append(f"  last written: {d.writer.describe()}")
    if context and expected is not None and actual is not None:
        lines.append(f"context ({context} scan(s) before):")
        lines += context_rows(expected, actual, d, context)
    return "\n".join(lines) + "\n"


# --- who wrote it -----------------------------------------------------------------------------

def locate_writer(spec, actual: Trace, divergence: Divergence, project=None) -> Writer | None:
    """Replay `spec` and find the statement that last wrote the diverging variable (None when
    the divergence is not a variable's value, or the variable cannot be resolved)."""
    if divergence.kind != "value":
        return None
    from stvm.runtime.vm import RuntimeFault   # lazy: start-up
    index = actual.index_of(divergence.variable)
    target_scan = actual.last_change(index, min(divergence.scan, actual.scans - 1))
    prepared = trace_session(spec, project)
    vm = prepared.vm
    try:
        signal = select_signals(vm, [divergence.variable])[0]
    except WatchError:
        return None
    prepared.wire()
    try:
        for _ in range(target_scan):
            vm.scan()
        before = _read(signal.root, signal.steps)
        finder = _WriteFinder(vm, signal)
        sys.settrace(finder.global_trace)
        try:
            vm.scan()
        finally:
            sys.settrace(None)
    except RuntimeFault:
        return None
    finally:
        vm.close()
    if finder.span is not None:
        return Writer(target_scan, finder.span, _source_line(prepared.project.sources, finder.span))
    previous = actual.value_at(index, target_scan - 1) if target_scan > 0 else None
    if target_scan == 0:
        return Writer(0, note="initial value or scenario [set]")
    if before is not None and previous is not None:
        return Writer(target_scan, note="set by the scenario before the scan")
    return None


def _read(root, steps):
    value = root
    for step in steps:
        value = value[step] if isinstance(step, int) else getattr(value, step)
    return value


def _source_line(sources: dict, span) -> str:
    text = sources.get(span.file)
    if text is None:
        return ""
    lines = text.splitlines()
    return lines[span.line - 1] if 0 < span.line <= len(lines) else ""


class _WriteFinder:
    """Line tracer over generated code: remembers the statement after which the value changed."""

    def __init__(self, vm, signal) -> None:
        from stvm.runtime.vm import GENERATED_FILENAME   # lazy: start-up
        self.filename = GENERATED_FILENAME
        self.line_map = vm.project.lowered.line_map
        self.root = signal.root
        self.steps = signal.steps
        self.key = signal.steps[-1] if signal.steps and isinstance(signal.steps[-1], str) else None
        self.last = self._value(None)
        self.frame_lines: dict = {}   # frame -> its last line with an ST statement
        self.span = None

    def _container(self):
        return _read(self.root, self.steps[:-1]) if self.steps else None

    def _value(self, frame):
        container = self._container()
        key = self.key
        if key is not None:
            # a program/FB body keeps its scalars in locals while it runs: the innermost such
            # frame holds the current value
            while frame is not None:
                code = frame.f_code
                if code.co_filename == self.filename and key in code.co_varnames:
                    local_vars = frame.f_locals
                    if local_vars.get("self") is container and key in local_vars:
                        return local_vars[key]
                frame = frame.f_back
        try:
            return _read(self.root, self.steps)
        except (AttributeError, IndexError, TypeError):
            return None

    def global_trace(self, frame, event, arg):
        if frame.f_code.co_filename != self.filename:
            return None
        return self.local_trace

    def local_trace(self, frame, event, arg):
        # The statement to blame is the last one of the frame in which the change shows: a
        # change seen in a caller after a FUNCTION, METHOD or interface call returned was made by
        # the caller's statement (`x := F(n)` assigns after F's last line ran), and one seen in
        # the callee by the callee's. One last line per frame, not one for the whole trace.
        if event in ("line", "return"):
            value = self._value(frame)
            if value != self.last:
                line = self.frame_lines.get(frame)
                span = self.line_map.span_at(line) if line is not None else None
                if span is not None:
                    self.span = span
            self.last = value
            if event == "line" and self._owns(frame):
                self.frame_lines[frame] = frame.f_lineno
            elif event == "return":
                self.frame_lines.pop(frame, None)
        return self.local_trace

    def _owns(self, frame) -> bool:
        """Whether the line has an ST statement of its own: lines of a native FB's wrapper have
        none, and `LineMap.span_at` would answer with the previous POU's last statement."""
        lines = self.line_map.lines
        i = bisect.bisect_right(lines, frame.f_lineno) - 1
        return i >= 0 and lines[i] >= frame.f_code.co_firstlineno
