"""The real-time deadline keeper (stvm/runtime/realtime.py): behaviour, not speed (the figures are
in bench/bench_realtime.py)."""

from __future__ import annotations

import gc
import time

import stvm
from core_helpers import write_st
from stvm.runtime import realtime

TOGGLE = "PROGRAM Main\nVAR x : BOOL; n : DINT; END_VAR\nx := NOT x;\nn := n + 1;\nEND_PROGRAM\n"


def test_wait_until_never_returns_before_the_deadline():
    pacer = realtime.Pacer()
    for offset_ns in (0, 50_000, 300_000, 1_000_000):
        deadline = time.perf_counter_ns() + offset_ns
        assert pacer.wait_until(deadline) >= deadline


def test_the_collector_is_held_during_a_real_time_run_and_given_back():
    assert gc.isenabled()
    vm = stvm.load([write_st(TOGGLE)]).start(scan="1ms", realtime=True)
    seen = []
    vm.on_scan_end.append(lambda _vm: seen.append((gc.isenabled(), gc.get_freeze_count() > 0)))
    vm.run(cycles=20)
    vm.close()
    assert vm["Main.n"] == 20 and vm.scan_count == 20
    assert set(seen) == {(False, True)}           # off and the heap frozen inside the loop
    assert gc.isenabled() and gc.get_freeze_count() == 0
    assert vm.pacer is not None and vm.jitter_ns.count == 20


def test_garbage_made_by_the_scans_is_collected_between_them(monkeypatch):
    monkeypatch.setattr(realtime, "GC_IDLE_NS", 0)       # always time enough
    pacer = realtime.Pacer()
    pacer.take_gc()
    try:
        threshold = gc.get_threshold()[0]
        for _ in range(threshold + 10):
            a = []
            a.append(a)                                   # a cycle: only the collector frees it
        pacer.wait_until(time.perf_counter_ns() + 2_000_000)
        assert pacer.gc_collections == 1
    finally:
        pacer.release_gc()
    assert gc.isenabled()


def test_a_virtual_clock_run_leaves_the_collector_alone():
    vm = stvm.load([write_st(TOGGLE)]).start(scan="1ms")
    seen = []
    vm.on_scan_end.append(lambda _vm: seen.append(gc.isenabled()))
    vm.run(cycles=3)
    assert seen == [True] * 3 and vm.pacer is None


def test_two_holders_share_the_collector_and_the_last_gives_it_back():
    first, second = realtime.Pacer(), realtime.Pacer()
    first.take_gc()
    second.take_gc()
    first.release_gc()
    assert not gc.isenabled()              # the second loop still runs
    second.release_gc()
    assert gc.isenabled() and gc.get_freeze_count() == 0
