"""The recorder: preallocated blocks, changes only, the same trace whatever the block size."""

from __future__ import annotations

from pathlib import Path

import pytest

from stvm.trace import Recorder, TraceSpec, run_trace, select_signals
from stvm.trace.writers import to_jsonl

COUNTER = Path(__file__).parent / "st" / "counter.st"


@pytest.fixture(scope="module")
def project():
    from stvm.project import load
    return load([COUNTER])


def record(project, cycles: int, block_rows: int):
    vm = project.start(scan="1ms")
    recorder = Recorder(vm, select_signals(vm, ["Main.*"]), block_rows=block_rows).attach()
    vm.run(cycles=cycles)
    return recorder.finish()


@pytest.mark.parametrize("block", [1, 2, 3, 7, 64])
def test_block_size_does_not_change_the_trace(project, block):
    assert to_jsonl(record(project, 20, block)) == to_jsonl(record(project, 20, 2048))


def test_only_changes_are_kept(project):
    trace = record(project, 20, 4)
    flag = trace.index_of("Main.flag")
    assert trace.series(flag) == ([0, 5], ["FALSE", "TRUE"])      # counter 6 > limit in scan 5
    counter = trace.index_of("Main.counter")
    assert trace.series(counter)[0] == list(range(20))
    txt = trace.index_of("Main.txt")
    assert trace.series(txt) == ([0, 2], ["''", "'three'"])
    t_q = trace.index_of("Main.t.Q")
    assert trace.series(t_q) == ([0, 8], ["FALSE", "TRUE"])        # PT 3 ms after IN in scan 5
    assert trace.value_at(trace.index_of("Main.r"), 3) == "2.0"
    assert trace.scans == 20 and trace.scan_ns == 1_000_000


def test_run_trace_records_a_runtime_fault(tmp_path):
    src = tmp_path / "div.st"
    src.write_text("PROGRAM Main\nVAR n : INT; d : INT := 3; END_VAR\nn := n + 1;\nd := d - 1;\nn := 10 / d;\nEND_PROGRAM\n")
    run = run_trace(TraceSpec([src], cycles=10, watch=["Main.*"]))
    assert run.fault is not None
    assert run.trace.scans == 3        # scans 0 and 1, then the sample the fault left in scan 2
    assert run.trace.events[-1].scan == 2 and "runtime fault: div.st:5" in run.trace.events[-1].text
