"""Does the debugger slow down `stvm run`? (issue 8: "zero cost when not debugging")

Run: python bench/bench_debug_overhead.py [--rounds 7]   (prints a table; no timed assertions)

Part 1 runs `stvm run FILE --cycles N --stats` on the core benchmark programs (bench/st/) in fresh
processes, three ways, interleaved round by round:

* absent:   `stvm.debug` blocked (`sys.modules["stvm.debug.cli"] = None`): the CLI as if the
            debugger did not exist;
* present:  the CLI as shipped (it imports `stvm.debug.cli` to register `debug` and `dap`);
* imported: the whole debugger (engine, scope compiler, console, DAP) imported before the run.

It reports the median over rounds of the mean scan time (`--stats`, measured inside the VM) and of
the process wall time (start-up included). The normal build is the same in all three (the debug
build is a separate lowering that `stvm run` never uses) and no trace function is installed, so
the expected difference is noise.

Part 2 (for information) shows what debugging costs: the same programs, and the thesis PnP
scenario with the robot in lockstep, run by the debug engine (debug build, breakpoints compiled in;
no breakpoint / one conditional breakpoint that never stops) against the normal VM, in-process.
bench/bench_debug_speed.py is the figure of issue 33 (CPU time, more programs).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ST = ROOT / "bench" / "st"
PROGRAMS = [("BOOL toggle", "bool_toggle.st", 200_000), ("FOR sum 100", "for_sum.st", 20_000),
            ("bubble sort 1000", "bubble_sort.st", 10)]

_PRELUDE = {
    "absent": "import sys; sys.modules['stvm.debug.cli'] = None\n",
    "present": "",
    "imported": "import stvm.debug.engine, stvm.debug.scope, stvm.debug.console, stvm.debug.dap\n",
}
_RUN = "import sys\nfrom stvm.cli import main\nsys.exit(main(sys.argv[1:]))\n"
_MEAN = re.compile(r"scan time us: mean ([0-9.]+)")


def run_once(variant: str, file: Path, cycles: int, env: dict) -> tuple[float, float]:
    """(mean scan µs from --stats, process wall seconds) of one `stvm run` in a fresh process."""
    code = _PRELUDE[variant] + _RUN
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", code, "run", str(file), "--cycles", str(cycles), "--stats"],
                          cwd=str(ROOT), env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    match = _MEAN.search(done.stdout)
    if not match:
        raise RuntimeError(f"no --stats line in: {done.stdout!r} {done.stderr!r}")
    return float(match.group(1)), wall


def bench_run(rounds: int) -> None:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env["STVM_CACHE_DIR"] = tempfile.mkdtemp(prefix="stvm-bench-debug-")
    # bytecode cached as in a normal install, but outside the source tree
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = tempfile.mkdtemp(prefix="stvm-bench-pycache-")
    variants = list(_PRELUDE)
    print(f"Part 1: `stvm run FILE --cycles N --stats`, a fresh process per run, {rounds} rounds "
          f"(best and median; the machine's load shows in the median)")
    print(f"{'program':18} {'variant':9} {'scan µs best':>13} {'median':>10} {'vs absent':>10} "
          f"{'wall s best':>12} {'vs absent':>10}")
    for label, file, cycles in PROGRAMS:
        path = ST / file
        run_once("present", path, 1, env)   # warm the compile cache: every variant loads from it
        scans: dict[str, list[float]] = {v: [] for v in variants}
        walls: dict[str, list[float]] = {v: [] for v in variants}
        for _ in range(rounds):
            for variant in variants:
                scan_us, wall = run_once(variant, path, cycles, env)
                scans[variant].append(scan_us)
                walls[variant].append(wall)
        base_scan, base_wall = min(scans["absent"]), min(walls["absent"])
        for variant in variants:
            best, median, wall = min(scans[variant]), statistics.median(scans[variant]), min(walls[variant])
            print(f"{label if variant == 'absent' else '':18} {variant:9} {best:13.2f} {median:10.2f} "
                  f"{best / base_scan:9.3f}x {wall:12.3f} {wall / base_wall:9.3f}x")
    imports = []
    for _ in range(rounds):
        code = ("import time, importlib, stvm.cli\nt = time.perf_counter()\n"
                "importlib.import_module('stvm.debug.cli')\nprint((time.perf_counter() - t) * 1e6)\n")
        done = subprocess.run([sys.executable, "-c", code], cwd=str(ROOT), env=env, capture_output=True,
                              text=True, check=True)
        imports.append(float(done.stdout))
    print(f"importing stvm/debug/cli.py after stvm.cli (what every `stvm` command pays for the debugger): "
          f"{statistics.median(imports):.0f} µs (median of {rounds} fresh processes, bytecode cached)")


def _thesis_vm(project, scan_ns: int):
    """The thesis PnP scenario with the robot in lockstep, wired as `stvm trace` wires it."""
    from stvm.lockstep import LockstepTransport
    from stvm.scenario import ScenarioDriver, load_scenario
    transport = LockstepTransport()
    vm = project.start(scan=scan_ns, transport=transport)
    scenario = load_scenario(ROOT / "st_src" / "scenarios" / "pnp_demo.toml")
    driver = ScenarioDriver(scenario, vm, transport.inject_fault)
    vm.on_scan_end.append(driver.after_scan)
    transport.attach(vm)
    driver.apply_initial({scenario.robot_address: "'127.0.0.1'", scenario.robot_port: 5890})
    return vm


def bench_engine() -> None:
    sys.path.insert(0, str(ROOT))
    import stvm
    from stvm.debug.build import load_debug
    from stvm.debug.engine import SCAN, Engine
    from stvm.debug.session import SessionOptions, open_session
    thesis = str(ROOT / "st_src" / "PnP_Example.st")
    move_abs = str(ROOT / "st_src" / "CBT_MoveAbsolute.st")
    cases = [("BOOL toggle", str(ST / "bool_toggle.st"), 20000), ("FOR sum 100", str(ST / "for_sum.st"), 500),
             ("bubble sort 1000", str(ST / "bubble_sort.st"), 1), ("thesis PnP, lockstep", thesis, 3000)]
    print("\nPart 2 (information): µs per scan under the debugger, in-process (debug build, breakpoints compiled in).")
    print("'1 bp': a breakpoint with the condition FALSE (never stops, evaluated at every pass) on the")
    print("program's last statement (the thesis: CBT_MoveAbsolute line 103, two instances per scan)")
    print(f"{'program':22} {'stvm run':>10} {'debug, no bp':>13} {'ratio':>6} {'debug, 1 bp':>12} {'ratio':>6}")
    for label, path, cycles in cases:
        if path == thesis:
            vm = _thesis_vm(stvm.load([path], use_cache=False), 1_000_000)
        else:
            vm = stvm.load([path], use_cache=False).start(scan="1ms")
        vm.collect_stats = False
        start = time.perf_counter()
        vm.run(cycles=cycles)
        normal = (time.perf_counter() - start) / cycles
        vm.close()
        build = load_debug([path])
        results = []
        for with_bp in (False, True):
            if path == thesis:
                session = open_session(SessionOptions([path], scan="1ms",
                                                      scenario=str(ROOT / "st_src" / "scenarios" / "pnp_demo.toml")),
                                       build=build)
                engine = session.engine
            else:
                session, engine = None, Engine(build, scan_ns=1_000_000)
            engine.start()
            engine.wait_started(30)
            if with_bp:
                bp_file = move_abs if path == thesis else path
                bp_line = 103 if path == thesis else build.statements.st_lines[path][-1]
                engine.add_breakpoint(bp_file, bp_line, "FALSE")
            start = time.perf_counter()
            engine.run(SCAN, cycles, timeout=3600)
            results.append((time.perf_counter() - start) / cycles)
            if session is not None:
                session.close()
            else:
                engine.terminate()
        print(f"{label:22} {normal * 1e6:10.1f} {results[0] * 1e6:13.1f} {results[0] / normal:6.1f} "
              f"{results[1] * 1e6:12.1f} {results[1] / normal:6.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--skip-engine", action="store_true", help="only part 1")
    args = parser.parse_args()
    bench_run(args.rounds)
    if not args.skip_engine:
        bench_engine()


if __name__ == "__main__":
    main()
