"""Lockstep runs are bit-identical: 10 consecutive PnP runs write byte-identical trace files
(bench/bench_trace.py runs 100)."""

from __future__ import annotations

import hashlib
import importlib.util

from trace_helpers import SCENARIOS, THESIS
from stvm.trace import TraceSpec, run_trace, write_trace

RUNS = 10
HAVE_PYVCD = importlib.util.find_spec("vcd") is not None


def test_ten_pnp_runs_give_identical_files(tmp_path, thesis_project):
    spec = TraceSpec([THESIS / "PnP_Example.st"], scenario=SCENARIOS / "golden_pnp_cycle.toml")
    digests = set()
    for i in range(RUNS):
        # the first run loads the project itself (compile cache), the others share one Project
        run = run_trace(spec, None if i == 0 else thesis_project)
        assert run.fault is None
        files = write_trace(run.trace, tmp_path / f"run{i}.jsonl")
        if HAVE_PYVCD:
            files += write_trace(run.trace, tmp_path / f"run{i}.vcd")
        digests.add(tuple(hashlib.sha256(f.read_bytes()).hexdigest() for f in files))
    assert len(digests) == 1
