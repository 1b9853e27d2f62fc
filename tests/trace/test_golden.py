"""First-divergence comparison, the report, and finding the ST line that wrote a value."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest

from stvm.trace import TraceSpec, compare, locate_writer, render_report, run_trace
from stvm.trace.model import EventEntry, FrameEntry

ST = Path(__file__).parent / "st"
SPEC = TraceSpec([ST / "counter.st"], cycles=12, watch=["Main.*"])


@pytest.fixture(scope="module")
def base():
    return run_trace(SPEC).trace


def changed(trace, edit):
    other = copy.deepcopy(trace)
    other._series = None
    edit(other)
    other.changes.sort(key=lambda c: (c[0], c[1]))
    return other


def test_equal_traces(base):
    assert compare(base, copy.deepcopy(base)) is None


def test_first_value_difference_wins(base):
    flag = base.index_of("Main.flag")
    txt = base.index_of("Main.txt")

    def edit(t):
        t.changes = [c for c in t.changes if c[1] != flag] + [(7, flag, "TRUE"), (6, txt, "'x'")]
    d = compare(base, changed(base, edit))
    assert (d.scan, d.variable, d.expected, d.actual) == (5, "Main.flag", "TRUE", "FALSE")
    assert d.time_ns == 5_000_000
    assert d.summary().startswith("first divergence at scan 5 (t=T#5ms): Main.flag")


def test_same_scan_goes_by_signal_order(base):
    counter, flag = base.index_of("Main.counter"), base.index_of("Main.flag")

    def edit(t):
        t.changes = [(s, i, "99" if (s, i) == (5, counter) else v) for s, i, v in t.changes if (s, i) != (5, flag)]
    assert compare(base, changed(base, edit)).variable == "Main.counter"


def test_events_frames_and_length(base):
    d = compare(base, changed(base, lambda t: t.events.append(EventEntry(4, "set X=1"))))
    assert (d.kind, d.scan, d.expected, d.actual) == ("event", 4, "<none>", "set X=1 (scan 4)")
    d = compare(base, changed(base, lambda t: t.frames.append(FrameEntry(3, 3_500_000, "tx", 1, "$CPERR,2,01,*49\r\n"))))
    assert (d.kind, d.scan, d.variable) == ("frame", 3, "emulator frame")
    shorter = run_trace(TraceSpec(SPEC.files, cycles=10, watch=SPEC.watch)).trace
    d = compare(base, shorter)
    assert (d.kind, d.scan, d.expected, d.actual) == ("length", 10, "12 scans", "10 scans")


def test_signal_set_and_period(base):
    fewer = run_trace(TraceSpec(SPEC.files, cycles=12, watch=["Main.counter"])).trace
    d = compare(base, fewer)
    assert d.kind == "signals" and d.actual == "<not recorded>"
    slower = run_trace(TraceSpec(SPEC.files, cycles=12, watch=SPEC.watch, scan="2ms")).trace
    assert compare(base, slower).kind == "period"


def test_report_with_context(base):
    flag = base.index_of("Main.flag")
    actual = changed(base, lambda t: setattr(t, "changes", [c for c in t.changes if c[1] != flag]))
    d = compare(base, actual)
    report = render_report(d, base, actual, context=2, golden_name="g.jsonl")
    lines = report.splitlines()
    assert lines[0] == "trace differs from g.jsonl: first divergence at scan 5 (t=T#5ms)"
    assert lines[1:4] == ["  variable: Main.flag", "  expected: TRUE", "  actual:   FALSE"]
    assert [line.split()[0] for line in lines[-3:]] == ["3", "4", "5"]
    assert "≠" in lines[-1]


@pytest.mark.parametrize(("variable", "statement"), [
    ("Main.flag", "flag := TRUE;"),                         # a cached local of the program body
    ("Main.t.Q", "t(IN := flag, PT := T#3ms);"),            # a native FB's output: the call
    ("Main.arr[1]", "arr[counter MOD 4] := counter;"),      # an array element
    ("Main.pair.a", "pair.a := counter * 2;"),              # a struct field
])
def test_locate_writer(base, variable, statement):
    index = base.index_of(variable)
    last = base.series(index)[0][-1]

    def edit(t):
        t.changes = [c for c in t.changes if not (c[1] == index and c[0] == last)]
    expected = changed(base, edit)
    d = compare(expected, base)
    assert d.variable == variable and d.scan == last
    writer = locate_writer(SPEC, base, d)
    assert writer is not None and writer.scan == last
    assert writer.source_line.strip() == statement
    assert f"counter.st:{writer.span.line}:" in writer.describe()


def test_locate_writer_for_a_value_set_before_the_run(base):
    index = base.index_of("Main.limit")
    expected = changed(base, lambda t: t.initial.__setitem__(index, "6"))
    d = compare(expected, base)
    writer = locate_writer(SPEC, base, d)
    assert writer.span is None and "initial value" in writer.note
