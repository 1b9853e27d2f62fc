"""Soak benchmark (issue 17): memory and open files stay flat on long runs.

Run: python bench/bench_soak.py [--scans 1000000] [--realtime-seconds 600]

1. Lockstep: the thesis PnP project with the in-process TM emulator on the virtual clock
   (st_src/scenarios/pnp_demo.toml: connect, then Pick-and-Place cycles for ever), `--scans`
   scans. RSS, open file descriptors and Python's allocated blocks are sampled every tenth of the
   run; the growth after the first tenth (warm-up: caches, first motions) is the figure.
2. Real time: `stvm run st_src/PnP_Example.st --scan 1ms --duration Ns` as a child process
   (the demo: bundled emulator on a loopback TCP port, real-time clock, a status line a
   second), RSS and open files of the child sampled every 10 s from /proc.

Prints one table per part and the growth per million scans / per hour. No assertions: the
regression test with a bound is tests/runtime/test_runtime_memory.py.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

PAGE = os.sysconf("SC_PAGE_SIZE")


def rss_mb(pid: int | str = "self") -> float:
    with open(f"/proc/{pid}/statm") as fh:
        return int(fh.read().split()[1]) * PAGE / 2**20


def open_fds(pid: int | str = "self") -> int:
    return len(os.listdir(f"/proc/{pid}/fd"))


def lockstep_soak(scans: int) -> None:
    from stvm.trace.run import TraceSpec, trace_session   # the run_trace wiring, without a recorder
    spec = TraceSpec([ROOT / "st_src" / "PnP_Example.st"], scenario=ROOT / "st_src" / "scenarios" / "pnp_demo.toml",
                     scan="1ms")
    prepared = trace_session(spec)
    prepared.wire()
    vm = prepared.vm
    step = prepared.project.manifest["demo"]["step_variable"]
    cycles, last = 0, None
    print(f"lockstep soak: {scans:,} scans of the PnP demo (1 ms, virtual clock); load {os.getloadavg()[0]:.2f}")
    print(f"{'scans':>10} {'VM time s':>10} {'PnP cycles':>10} {'RSS MB':>8} {'fds':>5} {'py blocks':>10} {'scans/s':>8}")
    every = max(1, scans // 10)
    samples = []
    started = time.perf_counter()
    lap = started
    for i in range(1, scans + 1):
        vm.scan()
        value = vm.get(step)
        if value != last:
            if last == 26 and value == 10:
                cycles += 1
            last = value
        if i % every == 0 or i == scans:
            now = time.perf_counter()
            rate = every / (now - lap) if now > lap else 0.0
            lap = now
            sample = (i, rss_mb(), open_fds(), sys.getallocatedblocks())
            samples.append(sample)
            print(f"{i:>10,} {vm.now_ns / 1e9:>10.1f} {cycles:>10} {sample[1]:>8.1f} {sample[2]:>5} {sample[3]:>10,} {rate:>8.0f}")
    vm.close()
    first, final = samples[0], samples[-1]
    span = (final[0] - first[0]) / 1e6 or 1.0
    print(f"growth after the first tenth: RSS {final[1] - first[1]:+.1f} MB, fds {final[2] - first[2]:+d}, "
          f"blocks {final[3] - first[3]:+,} ({(final[1] - first[1]) / span:+.2f} MB per million scans); "
          f"{cycles} PnP cycles in {time.perf_counter() - started:.0f} s wall")


def realtime_soak(seconds: int) -> None:
    cmd = [sys.executable, "-m", "stvm", "run", str(ROOT / "st_src" / "PnP_Example.st"), "--scan", "1ms",
           "--duration", f"{seconds}s"]
    env = dict(os.environ)
    print(f"\nreal-time soak: {' '.join(cmd[2:])}; load {os.getloadavg()[0]:.2f}")
    print(f"{'t s':>6} {'RSS MB':>8} {'fds':>5}")
    samples = []
    with open(os.devnull, "wb") as sink:
        proc = subprocess.Popen(cmd, stdout=sink, stderr=subprocess.PIPE, env=env, cwd=ROOT)
        started = time.monotonic()
        interval = 10 if seconds >= 60 else 1
        try:
            while proc.poll() is None:
                time.sleep(interval)
                if proc.poll() is not None:
                    break
                t = time.monotonic() - started
                try:
                    sample = (t, rss_mb(proc.pid), open_fds(proc.pid))
                except OSError:
                    break
                samples.append(sample)
                if len(samples) == 1 or len(samples) % 6 == 0:
                    print(f"{t:>6.0f} {sample[1]:>8.1f} {sample[2]:>5}")
            _, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    print(err.decode(errors="replace").strip()[-600:])
    if len(samples) >= 3:
        # the first 10 % are warm-up (imports done, first motions, caches)
        base = samples[max(1, len(samples) // 10)]
        final = samples[-1]
        hours = (final[0] - base[0]) / 3600 or 1.0
        print(f"growth from t={base[0]:.0f}s to t={final[0]:.0f}s: RSS {final[1] - base[1]:+.1f} MB "
              f"({(final[1] - base[1]) / hours:+.1f} MB/hour), fds {final[2] - base[2]:+d}; exit {proc.returncode}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", type=int, default=1_000_000)
    parser.add_argument("--realtime-seconds", type=int, default=600)
    args = parser.parse_args()
    if args.scans > 0:
        lockstep_soak(args.scans)
    if args.realtime_seconds > 0:
        realtime_soak(args.realtime_seconds)


if __name__ == "__main__":
    main()
