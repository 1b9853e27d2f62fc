"""Real-time scan loop (issue 16, item 6): overruns and wake-up jitter at 1 ms, and what each
technique of stvm/runtime/realtime.py is worth.

Run: python bench/bench_realtime.py [--seconds 60] [--ablation-seconds 10] [--program FILE]

1. The command a user runs, as a fresh process:
   `stvm run bench/st/for_sum.st --scan 1ms --duration 60s --realtime`, its report line parsed:
   overruns as a share of the scans (target <= 0.1 %) and the start-jitter p99 (<= 200 us).
   The same with STVM_RT_PRIORITY=10 (SCHED_FIFO) when the user may use it.
2. Ablation, in one process, each for --ablation-seconds: the loop as it was before (relative
   sleep, default timer slack, the collector free to run inside scans), then each technique
   added in turn (timer slack 1 ns, a 200 us spin before the deadline, the collector between
   scans), the default at normal priority (no spin), then SCHED_FIFO without and with the spin
   (the default in a real-time class).

The load average is printed with every figure: on a shared machine the scheduler, not stvm,
sets the floor. No pass/fail: the figures are printed side by side with their targets.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

REPORT = re.compile(r"realtime: (\d+) scans, overruns (\d+) .*?catch-up scans (\d+), max lateness (\d+) us; "
                    r"start jitter us: p50 (\d+)\s+p99 (\d+)\s+max (\d+)")


def load() -> str:
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def machine() -> str:
    import platform
    return f"{platform.node()} ({os.cpu_count()} cores, {platform.machine()}, Python {platform.python_version()})"


def run_cli(program: str, seconds: float, env_extra: dict[str, str]) -> str:
    env = dict(os.environ, **env_extra)
    before = load()
    out = subprocess.run([sys.executable, "-m", "stvm", "run", program, "--scan", "1ms",
                          "--duration", f"{seconds:g}s", "--realtime"],
                         capture_output=True, text=True, env=env, cwd=ROOT, timeout=seconds * 3 + 60)
    m = REPORT.search(out.stderr)
    if not m:
        return f"no report (exit {out.returncode}): {out.stderr.strip()[:300]}"
    scans, overruns, catch_up, worst, p50, p99, jmax = map(int, m.groups())
    return (f"{scans} scans, overruns {overruns} = {100 * overruns / scans:.3f} % (target <= 0.1 %), "
            f"catch-up {catch_up}, jitter p50 {p50} us, p99 {p99} us (target <= 200 us), max {jmax} us; "
            f"{before} -> {load()}")


def run_in_process(program: str, seconds: float, *, spin_ns: int, manage_gc: bool, slack: int | None,
                   fifo: bool) -> str:
    import stvm
    from stvm.runtime import realtime
    realtime.SPIN_NS = realtime.SPIN_NS_NORMAL = spin_ns
    realtime.MANAGE_GC, realtime.TIMER_SLACK_NS = manage_gc, slack
    if fifo:
        os.environ["STVM_RT_PRIORITY"] = "10"
    else:
        os.environ.pop("STVM_RT_PRIORITY", None)
    before = load()
    vm = stvm.load([program]).start(scan="1ms", realtime=True)
    vm.run(duration_ns=int(seconds * 1e9))
    vm.close()
    _, p50, p99, jmax = vm.jitter_ns.summary_us()
    policy = vm.pacer.policy
    if fifo and hasattr(os, "sched_setscheduler"):     # back to normal for the next variant
        try:
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        except OSError:
            pass
    return (f"{vm.scan_count} scans, overruns {vm.overruns} = {100 * vm.overruns / vm.scan_count:.3f} %, "
            f"catch-up {vm.catch_up_scans}, jitter p50 {p50:.0f} us, p99 {p99:.0f} us, max {jmax:.0f} us, "
            f"gc between scans {vm.pacer.gc_collections}, {policy}; {before}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=60.0, help="length of the CLI runs (default 60)")
    ap.add_argument("--ablation-seconds", type=float, default=10.0, help="length of each ablation run (0: none)")
    ap.add_argument("--program", default=str(ROOT / "bench" / "st" / "for_sum.st"))
    args = ap.parse_args()
    print(f"machine: {machine()}; {load()}")
    print(f"program: {Path(args.program).relative_to(ROOT) if Path(args.program).is_absolute() else args.program}, "
          f"1 ms period")
    print(f"\n`stvm run --realtime` for {args.seconds:g} s (fresh process):")
    print(f"  default      : {run_cli(args.program, args.seconds, {})}")
    print(f"  SCHED_FIFO 10: {run_cli(args.program, args.seconds, {'STVM_RT_PRIORITY': '10'})}")
    if args.ablation_seconds > 0:
        print(f"\nablation, {args.ablation_seconds:g} s each (one process):")
        variants = [
            ("before (sleep only)", dict(spin_ns=0, manage_gc=False, slack=None, fifo=False)),
            ("+ timer slack 1 ns", dict(spin_ns=0, manage_gc=False, slack=1, fifo=False)),
            ("+ 200 us spin", dict(spin_ns=200_000, manage_gc=False, slack=1, fifo=False)),
            ("+ gc between scans", dict(spin_ns=200_000, manage_gc=True, slack=1, fifo=False)),
            ("no spin, gc, slack", dict(spin_ns=0, manage_gc=True, slack=1, fifo=False)),
            ("+ SCHED_FIFO 10", dict(spin_ns=0, manage_gc=True, slack=1, fifo=True)),
            ("+ 200 us spin", dict(spin_ns=200_000, manage_gc=True, slack=1, fifo=True)),
        ]
        for name, knobs in variants:
            print(f"  {name:<20}: {run_in_process(args.program, args.ablation_seconds, **knobs)}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
