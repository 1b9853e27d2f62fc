"""Where the thesis PnP scan spends its time: a per-POU profile of the generated code.

Runs the thesis PnP scenario with the robot in lockstep (as `stvm trace` wires it), first
unprofiled for the median ST time per scan (the VM's own `scan_durations_ns`) next to the
yardstick of `bench/bench_core.py` (the hand-written Python FOR-100 loop), then under cProfile,
and attributes every function's own time to the POU whose generated class (or to the stdlib /
emulator module) it belongs to. Printed as µs per scan, calls per scan and share of the total,
largest first — the table issue 16 asks to publish before changing the lowering.

    python bench/profile_scan.py                 # 20,000 scans timed, 10,000 profiled
    python bench/profile_scan.py --scans 5000 --top 15
    python bench/profile_scan.py --opcodes       # bytecodes and Python calls per scan instead
    python bench/profile_scan.py --opcodes --phase moving   # only scans while the robot moves
    python bench/profile_scan.py --run-only 4300  # load and run, nothing else (for valgrind)

The scenario alternates two phases of about 2 s: the robot waiting at a pick or place point
(the program's TON runs) and a motion running (CBT_MoveAbsolute polls its receive FB for the
motion's TMSTA every scan); the timing line is printed for each phase apart as well.

`--opcodes` counts what the interpreter executes (sys.settrace opcode events) over 500 scans:
exact and the same on every run, so it compares two builds on a loaded machine where timings
swing by 2×. A bytecode is not a fixed cost (a call costs far more than a local load), so the
number of Python calls is printed beside it.
"""

from __future__ import annotations

import argparse
import bisect
import cProfile
import pstats
import re
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from stvm.project import load  # noqa: E402
from stvm.runtime.stats import TimingStats  # noqa: E402
from stvm.runtime.vm import GENERATED_FILENAME, timing_us  # noqa: E402

THESIS = ROOT / "st_src" / "PnP_Example.st"
SCENARIO = ROOT / "st_src" / "scenarios" / "pnp_demo.toml"
_CLASS = re.compile(r"^class (\w+)|^def (\w+)")


def thesis_vm(project, scan_ns: int = 1_000_000):
    """The thesis PnP scenario with the robot in lockstep, wired as `stvm trace` wires it."""
    from stvm.lockstep import LockstepTransport
    from stvm.scenario import ScenarioDriver, load_scenario
    transport = LockstepTransport()
    vm = project.start(scan=scan_ns, transport=transport)
    scenario = load_scenario(SCENARIO)
    driver = ScenarioDriver(scenario, vm, transport.inject_fault)
    vm.on_scan_end.append(driver.after_scan)
    transport.attach(vm)
    driver.apply_initial({scenario.robot_address: "'127.0.0.1'", scenario.robot_port: 5890})
    return vm


def pou_of_line(project):
    """A function: generated line number -> the ST POU (or struct) whose class holds it."""
    names = {py: key for key, py in project.lowered.classes.items()}
    starts, owners = [], []
    for number, line in enumerate(project.lowered.source.splitlines(), 1):
        m = _CLASS.match(line)
        if m:
            py = m.group(1) or m.group(2)
            starts.append(number)
            owners.append(names.get(py, py))

    def owner(line: int) -> str:
        i = bisect.bisect_right(starts, line) - 1
        return owners[i] if i >= 0 else "<module>"
    return owner


def yardstick_us() -> float:
    """The hand-written Python FOR-100 loop of bench_core.py, best of 5 (µs per call)."""
    from bench_core import HandForSum, best_of
    return best_of(HandForSum(), repeat=5, number=2000) * 1e6


def where_of(file: str, name: str, owner) -> str:
    """The row of the table a function's code belongs to."""
    if file == GENERATED_FILENAME:
        return f"ST {owner}" + ("" if name == "__call__" else f".{name}")
    if "/stvm/stdlib/" in file:
        return f"stdlib {Path(file).stem}.{name}"
    if "/emulator/" in file:
        return "emulator (lockstep robot)"
    if "/stvm/runtime/" in file:
        return f"runtime {Path(file).stem}.{name}"
    if "/stvm/" in file:
        return f"{Path(file).stem}.{name} (scenario, lockstep hooks)"
    return "other (Python, builtins)"


def robot_moving(vm) -> bool:
    """Whether the emulated robot runs a motion (the phase the next scan belongs to)."""
    return bool(vm.ctx.transport.link.core.robot.executor.active)


def opcode_table(project, vm, scans: int, top: int, phase: str = "all") -> None:
    """Bytecodes and Python calls per scan, by POU (see the module docstring); with `phase`
    "moving" or "waiting" only scans of that phase are counted (`scans` of them)."""
    owner = pou_of_line(project)
    ops: dict[str, int] = {}
    calls: dict[str, int] = {}

    def tracer(frame, event, arg):
        code = frame.f_code
        line = code.co_firstlineno if code.co_filename == GENERATED_FILENAME else 0
        where = where_of(code.co_filename, code.co_name, owner(line + 1) if line else "")
        calls[where] = calls.get(where, 0) + 1
        frame.f_trace_opcodes = True
        frame.f_trace_lines = False

        def local(frame, event, arg):
            if event == "opcode":
                ops[where] = ops.get(where, 0) + 1
            return local
        return local
    if phase == "all":
        sys.settrace(tracer)
        try:
            vm.run(cycles=scans)
        finally:
            sys.settrace(None)
    else:
        counted, scan = 0, vm.scan
        for _ in range(100 * scans):          # the phases alternate every ~2,000 scans
            if robot_moving(vm) != (phase == "moving"):
                scan()
                continue
            sys.settrace(tracer)
            try:
                scan()
            finally:
                sys.settrace(None)
            counted += 1
            if counted == scans:
                break
        scans = max(counted, 1)
    total_ops, total_calls = sum(ops.values()), sum(calls.values())
    print(f"\nbytecodes per scan over {scans} scans ({phase}): {total_ops / scans:.0f}, Python calls per scan: "
          f"{total_calls / scans:.1f}")
    print(f"{'where':58} {'bytecodes':>9} {'calls':>6} {'share':>6}")
    for where, count in sorted(ops.items(), key=lambda kv: -kv[1])[:top]:
        print(f"{where[:58]:58} {count / scans:9.1f} {calls.get(where, 0) / scans:6.1f} {count / total_ops:6.1%}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scans", type=int, default=20000)
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--opcodes", action="store_true", help="bytecodes and calls per scan (exact, no timing)")
    ap.add_argument("--phase", choices=("all", "moving", "waiting"), default="all",
                    help="--opcodes: count only the scans while the robot moves, or while it waits")
    ap.add_argument("--run-only", type=int, metavar="N",
                    help="only load and run N scans, then exit: under an instruction counter the "
                         "difference of two N is what the scans between cost (see the README)")
    args = ap.parse_args()
    project = load([str(THESIS)], use_cache=False)
    vm = thesis_vm(project)
    if args.run_only is not None:
        vm.run(cycles=args.run_only)
        vm.close()
        return
    vm.run(cycles=2000)                        # connected and moving before anything is timed
    if args.opcodes:
        opcode_table(project, vm, 500, args.top, args.phase)
        vm.close()
        return
    vm.scan_durations_ns = TimingStats(window=args.scans)   # every scan's ST time kept, in order
    loop, moving, clock, scan = [], [], time.perf_counter_ns, vm.scan
    for _ in range(args.scans):
        moving.append(robot_moving(vm))
        started = clock()
        scan()
        loop.append(clock() - started)
    st_each = vm.scan_durations_ns.recent()
    loop_us = statistics.median(loop) / 1000
    loop_mean = sum(loop) / len(loop) / 1000
    st_us = timing_us(vm.scan_durations_ns)[1]
    hand = yardstick_us()
    print(f"thesis PnP in lockstep, {args.scans} scans: median ST time {st_us:.1f} µs per scan, whole loop "
          f"(with the emulator) median {loop_us:.1f} µs per scan (mean {loop_mean:.1f} µs: the scans that "
          f"build a command and the robot's motion planning)")
    print(f"yardstick: hand-written Python FOR-100 loop {hand:.1f} µs; ST scan / yardstick = {st_us / hand:.2f}× "
          f"(issue 16 target: ≤ 15 µs, ≤ 2.3×); whole loop / yardstick = {loop_us / hand:.2f}× (target ≤ 20 µs)")
    for name, want in (("motion running", True), ("robot waiting", False)):
        picked = [i for i, m in enumerate(moving) if m == want]
        if picked:
            print(f"  {name:14} ({len(picked):5} scans): median ST {statistics.median(st_each[i] for i in picked) / 1000:.1f} µs, "
                  f"whole loop {statistics.median(loop[i] for i in picked) / 1000:.1f} µs")

    profiled = max(args.scans // 2, 1)
    profile = cProfile.Profile()
    profile.enable()
    vm.run(cycles=profiled)
    profile.disable()
    owner = pou_of_line(project)
    rows: dict[str, list[float]] = {}
    stats = pstats.Stats(profile).stats   # (file, line, name) -> (cc, nc, tottime, cumtime, callers)
    for (file, line, name), (_, calls, own, _, _) in stats.items():
        where = where_of(file, name, owner(line) if file == GENERATED_FILENAME else "")
        row = rows.setdefault(where, [0.0, 0])
        row[0] += own
        row[1] += calls
    total = sum(r[0] for r in rows.values())
    print(f"\nper-POU profile (cProfile, {profiled} scans; profiled times are inflated, the shares are what count)")
    print(f"{'where':58} {'µs/scan':>8} {'calls/scan':>10} {'share':>6}")
    for where, (own, calls) in sorted(rows.items(), key=lambda kv: -kv[1][0])[:args.top]:
        print(f"{where[:58]:58} {own / profiled * 1e6:8.2f} {calls / profiled:10.1f} {own / total:6.1%}")
    vm.close()


if __name__ == "__main__":
    main()
