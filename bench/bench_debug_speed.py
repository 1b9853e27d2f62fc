"""Debugging at speed (issue 33, item 1): a scan under the debugger with breakpoints set but not
hit, against the same scan under `stvm run`, in the same process and run.

Run: python bench/bench_debug_speed.py [--smoke] [--rounds 3]   (prints a table; no timed assertions)

For each program the same scans (from scan 0) run several ways, interleaved round by round, best
of the rounds, CPU time (`time.process_time`: the debugger's worker thread included, the waiting
main thread costs nothing):

* `stvm run`: the normal build on the VM (the thesis: the scenario and the TM emulator in
  lockstep, wired as `stvm run --scenario` / `stvm trace` wire them);
* debugger, no breakpoint: the debug engine (`stvm debug` / `stvm dap` run the same engine)
  running the scans with `scan N`;
* debugger, a breakpoint not hit: one plain breakpoint on a statement the scans never reach;
* debugger, a conditional breakpoint on a hot line, condition FALSE (evaluated at every pass,
  never stops): for information, it is the cost of evaluating an ST condition.

Programs: the thesis PnP program (st_src/PnP_Example.st) with its demo scenario and the robot in
lockstep, and a FOR-loop-heavy program (bench/st/for_debug.st: 100 turns a scan). The yardstick
printed beside them is the plainest Python FOR-100 loop (`for i in range(1, 101): s = s + i`),
timed in the same run. Target: the debugger with breakpoints set but not hit ≤ 2x `stvm run`.

`run(smoke)` returns `bench.registry.Row`s for `python -m bench` (the yardstick is the registry's
`for_loop_us`).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench.registry import Row, for_loop_us  # noqa: E402

THESIS = ROOT / "st_src" / "PnP_Example.st"
MOVE_ABS = ROOT / "st_src" / "CBT_MoveAbsolute.st"
SCENARIO = ROOT / "st_src" / "scenarios" / "pnp_demo.toml"
FOR_DEBUG = ROOT / "bench" / "st" / "for_debug.st"


def _source_line(path: Path, text: str) -> int:
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if text in line:
            return number
    raise ValueError(f"{text!r} not in {path}")


def _thesis_vm(project):
    """The thesis scenario with the robot in lockstep, wired as `stvm trace` wires it."""
    from stvm.lockstep import LockstepTransport
    from stvm.scenario import ScenarioDriver, load_scenario
    transport = LockstepTransport()
    vm = project.start(scan=1_000_000, transport=transport)
    scenario = load_scenario(SCENARIO)
    driver = ScenarioDriver(scenario, vm, transport.inject_fault)
    vm.on_scan_end.append(driver.after_scan)
    transport.attach(vm)
    driver.apply_initial({scenario.robot_address: "'127.0.0.1'", scenario.robot_port: 5890})
    return vm


class Case:
    def __init__(self, label: str, path: Path, cycles: int, cold: tuple[Path, str], hot: tuple[Path, str]) -> None:
        self.label, self.path, self.cycles = label, path, cycles
        self.cold = (cold[0], _source_line(*cold))   # a statement the measured scans never reach
        self.hot = (hot[0], _source_line(*hot))      # a statement run at every scan (or turn)
        self.thesis = path == THESIS

    def run_us(self, project) -> float:
        vm = _thesis_vm(project) if self.thesis else project.start(scan="1ms")
        vm.collect_stats = False
        started = time.process_time()
        vm.run(cycles=self.cycles)
        spent = time.process_time() - started
        vm.close()
        return spent / self.cycles * 1e6

    def debug_us(self, build, breakpoint: str) -> float:
        from stvm.debug.engine import SCAN, SCANNED, Engine
        from stvm.debug.session import SessionOptions, open_session
        if self.thesis:
            session = open_session(SessionOptions([str(self.path)], scan="1ms", scenario=str(SCENARIO)), build=build)
            engine = session.engine
        else:
            session, engine = None, Engine(build, scan_ns=1_000_000)
        try:
            engine.start()
            engine.wait_started(60)
            if breakpoint == "cold":
                engine.add_breakpoint(str(self.cold[0]), self.cold[1])
            elif breakpoint == "hot":
                engine.add_breakpoint(str(self.hot[0]), self.hot[1], "FALSE")
            started = time.process_time()
            event = engine.run(SCAN, self.cycles, timeout=3600)
            spent = time.process_time() - started
            if event is None or event.reason != SCANNED:
                raise RuntimeError(f"{self.label}: the debugger stopped early: {event and event.describe()}")
        finally:
            if session is not None:
                session.close()
            else:
                engine.terminate()
        return spent / self.cycles * 1e6


def cases(smoke: bool) -> list[Case]:
    """The smoke version leaves the thesis out: building it twice (normal and debug) is most of a
    minute of CPU, and smoke numbers mean nothing."""
    thesis = Case("thesis PnP, robot in lockstep", THESIS, 3000,
                  cold=(MOVE_ABS, "ToErrorID:=16#99;"), hot=(MOVE_ABS, "R_TRIG_Execute(Clk:=Execute"))
    loop = Case("FOR-loop-heavy (100 turns)", FOR_DEBUG, 20 if smoke else 3000,
                cold=(FOR_DEBUG, "resets := resets + 1;"), hot=(FOR_DEBUG, "total := total + i * 7;"))
    return [loop] if smoke else [thesis, loop]


def measure(smoke: bool = False, rounds: int = 3) -> list[Row]:
    import stvm
    from stvm.debug.build import load_debug
    if smoke:
        rounds = 1
    rows: list[Row] = []
    yard = for_loop_us()
    for case in cases(smoke):
        project = stvm.load([str(case.path)], use_cache=False)
        build = load_debug([str(case.path)])
        best = {"run": float("inf"), "none": float("inf"), "cold": float("inf"), "hot": float("inf")}
        for _ in range(rounds):
            best["run"] = min(best["run"], case.run_us(project))
            for variant in ("none", "cold", "hot"):
                best[variant] = min(best[variant], case.debug_us(build, variant))
        yard = min(yard, for_loop_us())
        base = best["run"]
        cold_where = f"{case.cold[0].name}:{case.cold[1]}"
        hot_where = f"{case.hot[0].name}:{case.hot[1]}"
        label = f"debug speed: {case.label}"
        run_name = "`stvm run`, same scans"
        rows += [Row(f"{label}, `stvm run`", base, "µs/scan", "FOR-100", yard, "µs",
                     note="the yardstick for the rows below"),
                 Row(f"{label}, debugger, no breakpoint", best["none"], "µs/scan", run_name, base, "µs/scan", "<= 2x"),
                 Row(f"{label}, debugger, breakpoint set not hit", best["cold"], "µs/scan", run_name, base, "µs/scan",
                     "<= 2x", note=f"breakpoint at {cold_where}"),
                 Row(f"{label}, debugger, conditional breakpoint FALSE on a hot line", best["hot"], "µs/scan",
                     run_name, base, "µs/scan", note=f"condition evaluated at every pass of {hot_where}")]
    return rows


def run(smoke: bool) -> list[Row]:
    """The registry's entry point (`python -m bench`)."""
    return measure(smoke)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="a few scans (seconds; numbers mean nothing)")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    rows = measure(args.smoke, args.rounds)
    print(f"Python {sys.version.split()[0]}; CPU µs per scan, best of {1 if args.smoke else args.rounds} rounds")
    print(f"{'figure':92} {'value':>10} {'yardstick':>34} {'ratio':>7} {'target':>7}")
    for r in rows:
        yard = f"{r.yard_name} {r.yard:.1f} {r.yard_unit}"
        print(f"{r.figure:92} {r.value:10.1f} {yard:>34} {r.ratio:6.2f}x {r.target:>7}"
              + (f"  ({r.note})" if r.note else ""))


if __name__ == "__main__":
    main()
