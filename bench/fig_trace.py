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

import sys
import time
from pathlib import Path

if __name__ == "__main__":      # run as a script: the repository root makes `bench` importable
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.registry import ROOT, Row, figure, for_loop_us  # noqa: E402

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


_PARTS = (  # (where the innermost matching frame's code lives, the part): first match wins
    ("/emulator/", "emulator"),
    ("/stvm/lockstep.py", "lockstep glue (link, clock hook)"),
    ("/stvm/stdlib/sockets.py", "socket FBs' natives"),
    ("/stvm/trace/", "trace recorder"),
    ("<stvm-trace-sampler>", "trace recorder"),
    ("/stvm/scenario.py", "scenario"),
    ("<stvm-generated>", "ST programs (generated code, stdlib natives)"),
)
GLUE = "VM scan loop and the rest"


_ROOT_TEXT = str(ROOT)


def _classify(frame) -> str:
    while frame is not None:
        name = frame.f_code.co_filename
        if name.startswith(_ROOT_TEXT):
            # inside the repository: match on the path from its root (a checkout whose own path
            # holds "/emulator/", e.g. a worktree of that name, would otherwise match everything)
            name = name[len(_ROOT_TEXT):]
        for needle, part in _PARTS:
            if needle in name:
                return part
        frame = frame.f_back
    return GLUE


def parts(project, cycles: int, record: bool = True, interval_s: float = 0.0002, runs: int = 1) -> dict[str, float]:
    """CPU µs per scan of each part of the recorded (or bare) run: the loop's CPU time
    (`process_time`) shared out by a statistical profile on the process's CPU clock (SIGPROF
    every `interval_s` of CPU time; each sample goes to the part of the innermost frame that
    belongs to one, see `_PARTS`): time the process waits for a core is in neither, so the
    shares hold on a loaded machine (the kernel delivers SIGPROF at its tick, ~4 ms here, whatever
    `interval_s` asks: `runs` repeats the run for more samples). "loop" is the whole loop's CPU µs
    per scan."""
    import signal
    from stvm.trace import Recorder, TraceSpec, select_signals
    from stvm.trace.run import trace_session
    counts: dict[str, int] = {}

    def on_sample(signum, frame) -> None:
        part = _classify(frame)
        counts[part] = counts.get(part, 0) + 1

    cpu = 0.0
    for _ in range(runs):
        session = trace_session(TraceSpec(FILES, scenario=SCENARIO, watch=WATCH, cycles=cycles), project)
        vm = session.vm
        vm.collect_stats = False
        if record:
            recorder = Recorder(vm, select_signals(vm, WATCH))
            session.wire(recorder.sample)
            session.transport.on_frame.append(recorder.on_frame)
        else:
            session.wire()
        previous = signal.signal(signal.SIGPROF, on_sample)
        clock = time.process_time
        started = clock()
        signal.setitimer(signal.ITIMER_PROF, interval_s, interval_s)
        try:
            for _ in range(cycles):
                vm.scan()
        finally:
            signal.setitimer(signal.ITIMER_PROF, 0, 0)
            signal.signal(signal.SIGPROF, previous)
        cpu += clock() - started
        session.close()
    loop = cpu / runs / cycles * 1e6
    total = sum(counts.values()) or 1
    out = {part: loop * n / total for part, n in sorted(counts.items(), key=lambda kv: -kv[1])}
    out["loop"] = loop
    out["samples"] = total
    return out


def paired_ratios(measure, rounds: int) -> tuple[float, float, list[float]]:
    """`rounds` times: the FOR-100 yardstick, then `measure()` (CPU µs), back to back; (median
    value, median yardstick, the ratios). On a machine shared with other work the speed of both
    drifts over seconds; a ratio of two measurements taken together drifts less than a value
    set against a yardstick taken a minute earlier (a 9,200-scan run is ~0.4 s)."""
    import statistics
    values, yards, ratios = [], [], []
    for _ in range(rounds):
        yard = for_loop_us(rounds=3, number=1000)
        value = measure()
        values.append(value)
        yards.append(yard)
        ratios.append(value / yard)
    return statistics.median(values), statistics.median(yards), ratios


def bare_loop_us(project, cycles: int) -> float:
    """CPU µs per scan of `vm.scan()` with the scenario and the emulator, no recorder, no profiler."""
    from stvm.trace import TraceSpec
    from stvm.trace.run import trace_session
    session = trace_session(TraceSpec(FILES, scenario=SCENARIO, watch=WATCH, cycles=cycles), project)
    vm = session.vm
    vm.collect_stats = False
    session.wire()
    clock = time.process_time
    started = clock()
    for _ in range(cycles):
        vm.scan()
    spent = clock() - started
    session.close()
    return spent / cycles * 1e6


def _ratio_row(figure: str, ratios: list[float], value: float, yard: float, target: str, note: str) -> Row:
    import statistics
    spread = f"median of {len(ratios)} pair ratios ({min(ratios):.2f}-{max(ratios):.2f})"
    return Row(figure, value, "us", "FOR-100", yard, "us", target, ratio=statistics.median(ratios),
               note=f"{spread}; {note}" if note else spread)


@figure("stvm trace PnP golden, 1 watched", item="issue 33 item 2", tags=("trace",))
def trace_figure(smoke: bool) -> list[Row]:
    project = _project()
    cycles = SMOKE_CYCLES if smoke else CYCLES
    rounds = 1 if smoke else 5
    startup = [0.0]

    def traced() -> float:
        per_scan, startup[0] = trace_cpu_per_scan(project, cycles)
        return per_scan
    value, yard, ratios = paired_ratios(traced, rounds)
    rows = [_ratio_row("stvm trace PnP golden (1 watched var), CPU per scan", ratios, value, yard, "<= 2x",
                       f"{cycles} scans; set-up + finish {startup[0]:.0f} ms CPU subtracted")]
    runs = 1 if smoke else 4
    yard = for_loop_us()
    p = parts(project, cycles, runs=runs)
    bare = parts(project, cycles, record=False, runs=runs)
    yard = min(yard, for_loop_us())
    samples = p.pop("samples")
    for name, share in p.items():
        if name != "loop":
            rows.append(Row(f"  part: {name}", share, "us", "FOR-100", yard, "us", "",
                            note=f"{100 * share / p['loop']:.0f} % of the traced loop ({samples} CPU samples)"))
    bare.pop("samples")
    value, yard_bare, ratios = paired_ratios(lambda: bare_loop_us(project, cycles), rounds)
    rows.append(_ratio_row("bare lockstep loop (scenario + emulator, no recorder), CPU per scan", ratios, value,
                           yard_bare, "<= 4 us", ""))
    st = sum(v for k, v in bare.items() if k.startswith("ST programs"))
    rows.append(Row("  bare loop outside the ST programs", bare["loop"] - st, "us", "FOR-100", yard, "us", "",
                    note="emulator, lockstep glue, socket natives, scenario, VM loop (CPU profile shares)"))
    return rows


def opcode_parts(project, scans: int = CYCLES, top: int = 30) -> None:
    """The exact view, for a loaded machine: bytecodes and Python calls per scan of the traced
    golden run (recorder wired as in `parts`), per POU and Python module (bench/profile_scan.py's
    `opcode_table`: `sys.settrace` opcode events, the same on every run)."""
    from profile_scan import opcode_table
    from stvm.trace import Recorder, TraceSpec, select_signals
    from stvm.trace.run import trace_session
    session = trace_session(TraceSpec(FILES, scenario=SCENARIO, watch=WATCH, cycles=scans), project)
    vm = session.vm
    vm.collect_stats = False
    recorder = Recorder(vm, select_signals(vm, WATCH))
    session.wire(recorder.sample)
    session.transport.on_frame.append(recorder.on_frame)
    opcode_table(project, vm, scans, top)
    session.close()


if __name__ == "__main__":
    import argparse
    ap = argparse.ArgumentParser(description="the per-part tables of the traced PnP golden run")
    ap.add_argument("--opcodes", action="store_true",
                    help="bytecodes and Python calls per scan per POU (exact; ~1 min) instead of CPU shares")
    ap.add_argument("--scans", type=int, default=CYCLES)
    args = ap.parse_args()
    project = _project()
    if args.opcodes:
        opcode_parts(project, args.scans)
        raise SystemExit(0)
    print(f"FOR-100 yardstick {for_loop_us():.2f} us")
    for label, record in (("traced", True), ("bare", False)):
        p = parts(project, args.scans, record, runs=4)
        print(f"{label}: " + ", ".join(f"{k} {v:.2f}" for k, v in p.items()))
