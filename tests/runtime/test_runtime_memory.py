"""Long runs stay flat (issue 17): scan statistics and frame logs live in fixed-size structures.

The full soak (a million lockstep PnP scans, ten minutes real time) is bench/bench_soak.py;
these are the smaller runs with a bound. Memory bounds only: no timing is asserted.
"""

from __future__ import annotations

import gc
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import stvm
from stvm.runtime.stats import TimingStats

ROOT = Path(__file__).resolve().parents[2]

TOGGLE = "PROGRAM Main\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n"


def _traced_growth(step, warm: int, measured: int) -> int:
    """Bytes still allocated after `measured` more calls of `step` (after `warm` calls)."""
    for _ in range(warm):
        step()
    gc.collect()
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        for _ in range(measured):
            step()
        gc.collect()
        return tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()


def test_virtual_clock_run_does_not_grow_with_scans(tmp_path):
    path = tmp_path / "main.st"
    path.write_text(TOGGLE)
    vm = stvm.load([path]).start(scan="1ms")
    # 8 bytes per scan (the old per-scan list) would be 800 KB here
    growth = _traced_growth(vm.scan, warm=20_000, measured=100_000)
    assert growth < 64 * 1024, f"{growth} bytes retained over 100,000 scans"
    assert vm.scan_durations_ns.count == 120_000
    assert vm.scan_durations_ns.nbytes() < 64 * 1024


def test_realtime_jitter_statistics_are_bounded(tmp_path):
    path = tmp_path / "main.st"
    path.write_text(TOGGLE)
    vm = stvm.load([path]).start(scan="1ns", realtime=True)   # always behind: no sleeping
    growth = _traced_growth(vm.scan, warm=10_000, measured=50_000)
    assert growth < 64 * 1024
    assert vm.jitter_ns.count == 60_000
    # one stall episode is one overrun; every later scan catches up
    assert vm.overruns + vm.catch_up_scans == 60_000
    assert vm.overruns <= 10


def test_lockstep_pnp_run_is_flat():
    from stvm.trace.run import TraceSpec, trace_session
    spec = TraceSpec([ROOT / "st_src" / "PnP_Example.st"], scenario=ROOT / "st_src" / "scenarios" / "pnp_demo.toml",
                     scan="1ms")
    prepared = trace_session(spec)
    prepared.wire()
    vm = prepared.vm
    for _ in range(9_000):          # connected and one PnP cycle done: caches are warm
        vm.scan()
    gc.collect()
    blocks = sys.getallocatedblocks()
    for _ in range(9_000):          # one more full cycle
        vm.scan()
    gc.collect()
    grown = sys.getallocatedblocks() - blocks
    vm.close()
    assert vm.get("PnP_Example_Instance.Prg_Step") is not None
    # the bounded frame deque may still be filling (2 objects a frame, ~12 frames a cycle)
    assert grown < 2_000, f"{grown} Python blocks more after one PnP cycle"
    assert len(prepared.transport.frames) <= 1_000


# ---- the statistics structure itself


def test_timing_stats_are_exact_within_the_window():
    values = [5, 1, 9, 3, 7, 2, 8]
    stats = TimingStats(window=16)
    for v in values:
        stats.add(v)
    assert stats.summary_us() == pytest.approx((np.mean(values) / 1000, np.percentile(values, 50) / 1000,
                                                np.percentile(values, 99) / 1000, 0.009))
    assert list(stats.recent(3)) == [7, 2, 8]


def test_timing_stats_quantiles_within_bucket_precision_after_folding():
    rng = np.random.default_rng(17)
    values = rng.lognormal(11, 1.2, 50_000).astype(np.int64)
    stats = TimingStats(window=1000)
    for v in values.tolist():
        stats.add(v)
    assert stats.count == 50_000 and stats.maximum == values.max() and stats.minimum == values.min()
    assert stats.mean_ns == pytest.approx(values.mean())
    for q in (0.5, 0.9, 0.99):
        assert stats.quantile_ns(q) == pytest.approx(np.quantile(values, q), rel=0.02)
    assert list(stats.recent(5)) == values[-5:].tolist()
    assert stats.nbytes() < 40_000


def test_empty_stats_have_no_summary():
    assert TimingStats().summary_us() is None
