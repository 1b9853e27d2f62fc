"""Issue 33 item 2: `stvm trace` of the thesis PnP golden scenario with one watched variable.

* the CPU time per scan of the whole recorded run (`run_trace`, what `stvm trace` runs after
  start-up: the session's set-up and the trace's `finish` are measured by a 1-scan run and
  subtracted), against the FOR-100 yardstick (target <= 2x);
* where it goes, per part: the ST programs, the emulator's step (with the frames it hands to the
  recorder), the recorder's sample, the scenario's hook, and the VM's own scan loop around them;
* the bare lockstep loop (`vm.scan()` with the scenario and the emulator, no recorder) and its
  part outside the ST programs (target: the bare loop <= 4 µs).

Run alone: `python -m bench --only trace`; the part table: `python bench/fig_trace.py`.
"""

from __future__ import annotations

import time
from pathlib import Path

from bench.registry import ROOT, Row, figure, for_loop_us

SCENARIO = ROOT / "st_src" / "scenarios" / "golden_pnp_cycle.toml"
FILES = [ROOT / "st_src" / "PnP_Example.st"]
WATCH = ["PnP_Example_Instance.Prg_Step"]
CYCLES = 9200           # the scenario's [run] cycles: two full PnP cycles
SMOKE_CYCLES = 300


def _project():
    from stvm.project import load
    return load([str(f) for f in FILES])


def trace_cpu_per_scan(project, cycles: int) -> tuple[float, float]:
    """(CPU µs per scan of `run_trace` with start-up subtracted, start-up CPU ms)."""
    from stvm.trace import TraceSpec, run_trace
    clock = time.process_time
    startup = float("inf")
    for _ in range(3):   # the first also warms what a process does once (imports, caches)
        started = clock()
        run_trace(TraceSpec(FILES, scenario=SCENARIO, watch=WATCH, cycles=1), project)
        startup = min(startup, clock() - started)
    started = clock()
    run_trace(TraceSpec(FILES, scenario=SCENARIO, watch=WATCH, cycles=cycles), project)
    whole = clock() - started
    return (whole - startup) / (cycles - 1) * 1e6, startup * 1e3


class _Timed:
    """A hook wrapped with perf_counter_ns; `ns` accumulates its time."""

    def __init__(self, fn) -> None:
        self.fn, self.ns = fn, 0

    def __call__(self, *args) -> None:
        clock = time.perf_counter_ns
        started = clock()
        self.fn(*args)
        self.ns += clock() - started


def parts(project, cycles: int, record: bool = True) -> dict[str, float]:
    """µs per scan of each part of the recorded run (perf_counter_ns around each hook, the
    timer's own cost subtracted); "loop" is the whole `vm.scan()` as the caller sees it."""
    from stvm.trace import Recorder, TraceSpec, select_signals
    from stvm.trace.run import trace_session
    session = trace_session(TraceSpec(FILES, scenario=SCENARIO, watch=WATCH, cycles=cycles), project)
    vm = session.vm
    recorder = Recorder(vm, select_signals(vm, WATCH)) if record else None
    session.wire(recorder.sample if recorder else None)
    frames = None
    if recorder is not None:
        frames = _Timed(recorder.on_frame)
        session.transport.on_frame.append(frames)
    hooks = [_Timed(h) for h in vm.on_scan_end]
    vm.on_scan_end[:] = hooks
    names = {}
    for hook in hooks:
        owner = getattr(hook.fn, "__self__", None)
        names[id(hook)] = {"Recorder": "recorder sample", "ScenarioDriver": "scenario",
                           "LockstepTransport": "emulator step"}.get(type(owner).__name__, type(owner).__name__)
    clock = time.perf_counter_ns
    overhead = min(_timer_cost() for _ in range(3))
    started = clock()
    for _ in range(cycles):
        vm.scan()
    loop = clock() - started
    st = vm.scan_durations_ns.total
    out = {"ST programs": st / cycles / 1000}
    for hook in hooks:
        out[names[id(hook)]] = max(0.0, hook.ns / cycles - overhead) / 1000
    if frames is not None:
        out["recorder frames (inside the emulator step)"] = frames.ns / cycles / 1000
        out["emulator step"] -= out["recorder frames (inside the emulator step)"]
        out["recorder sample"] += out["recorder frames (inside the emulator step)"]
    accounted = sum(v for k, v in out.items() if not k.startswith("recorder frames"))
    # the VM's scan method: schedule, ctx, the stats, the hook loop, minus the timers we added
    out["VM scan loop (glue)"] = max(0.0, loop / cycles / 1000 - accounted - overhead * (len(hooks) + 1) / 1000)
    out["loop"] = loop / cycles / 1000
    session.close()
    return out


def _timer_cost() -> float:
    """ns of one `_Timed` wrapper around an empty function."""
    t = _Timed(lambda vm: None)
    n = 20000
    clock = time.perf_counter_ns
    started = clock()
    for _ in range(n):
        t(None)
    return (clock() - started) / n


@figure("stvm trace PnP golden, 1 watched", item="issue 33 item 2", tags=("trace",))
def trace_figure(smoke: bool) -> list[Row]:
    project = _project()
    cycles = SMOKE_CYCLES if smoke else CYCLES
    yard = for_loop_us()
    per_scan, startup = trace_cpu_per_scan(project, cycles)
    yard = min(yard, for_loop_us())
    rows = [Row("stvm trace PnP golden (1 watched var), CPU per scan", per_scan, "us", "FOR-100", yard, "us",
                "<= 2x", note=f"{cycles} scans; set-up + finish {startup:.0f} ms CPU subtracted")]
    p = parts(project, cycles)
    bare = parts(project, cycles, record=False)
    yard = min(yard, for_loop_us())
    for name, value in p.items():
        if name == "loop" or name.startswith("recorder frames"):
            continue
        rows.append(Row(f"  part: {name}", value, "us", "FOR-100", yard, "us", "",
                        note=f"{100 * value / p['loop']:.0f} % of the traced loop"))
    rows.append(Row("bare lockstep loop (scenario + emulator, no recorder)", bare["loop"], "us", "FOR-100", yard,
                    "us", "<= 4 us", note="median-free mean, perf_counter"))
    outside = bare["loop"] - bare["ST programs"]
    rows.append(Row("  bare loop outside the ST programs", outside, "us", "FOR-100", yard, "us", "",
                    note="emulator + scenario + VM glue"))
    return rows


if __name__ == "__main__":
    import sys
    sys.path.insert(0, str(ROOT))
    project = _project()
    print(f"FOR-100 yardstick {for_loop_us():.2f} us")
    for label, record in (("traced", True), ("bare", False)):
        p = parts(project, CYCLES, record)
        print(f"{label}: " + ", ".join(f"{k} {v:.2f}" for k, v in p.items()))
