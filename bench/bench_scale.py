"""Scale of a cell (issue 33, item 4): one controller, N robots, the thesis's V2 library.

Run: python bench/bench_scale.py [--smoke] [--scans 4000] [--profile N]   (prints tables; no timed assertions)

A cell of N robots (N = 1, 2, 4, 8, 16) is one VM at a 1 ms task running one program with N
CBT_Connect and N PnP_Sequence instances of the V2 library (st_src/cbt_v2, as
tests/cbt_v2/test_v2_four_robots.py runs four), and N TM emulators in lockstep on the VM's clock,
each at its own port. Every robot runs the demo's Pick-and-Place cycle for ever (its six targets,
shifted sideways by -75, -25, +25 or +75 mm, the offsets tests/cbt_v2/test_v2_four_robots.py
drives). After the connections are up (warm-up scans), the same window of scans is measured for
every N, in CPU time (`time.process_time`), split into the ST scan (the program) and the lockstep
hook (frame delivery and the N emulators).

A second series keeps one robot and adds idle copies of the per-robot FBs (CBT_Connect and
PnP_Sequence called every scan with Execute FALSE): scan cost against program size, in FB
instances (every ST FB instance in the program's tree, nested ones included).

Both series are fitted by least squares (slope, intercept, R²): the growth must be linear.
Target: ≤ 100 µs per scan at 16 robots. The yardstick printed beside each figure is the plainest
Python FOR-100 loop, timed in the same run.

`run(smoke)` returns `bench.registry.Row`s for `python -m bench` (the yardstick is the registry's
`for_loop_us`).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench.registry import Row, for_loop_us  # noqa: E402

V2 = ROOT / "st_src" / "cbt_v2"
DEMO_FILES = ("Globals.st", "PnP_Example.st", "Configuration.st")   # the demo program: not the cell's
SCENARIO = ROOT / "st_src" / "scenarios" / "pnp_demo.toml"
ROBOTS = (1, 2, 4, 8, 16)
IDLE = (0, 4, 8, 16)
BASE_PORT = 5890
_HARNESS_DIR = Path(tempfile.mkdtemp(prefix="stvm-bench-scale-"))


def harness(robots: int, idle: int = 0) -> str:
    """The cell's program: `robots` connections and PnP sequences, `idle` more never executed."""
    lib = "CBT_Commands_Lib_V2"
    idle_vars = idle_code = ""
    if idle:
        idle_vars = (f"    IdleCobots : ARRAY[1..{idle}] OF {lib}\\stCBT_Connection;\n"
                     f"    IdleConnects : ARRAY[1..{idle}] OF {lib}\\CBT_Connect;\n"
                     f"    IdleSequences : ARRAY[1..{idle}] OF {lib}\\PnP_Sequence;\n"
                     f"    IdlePaths : ARRAY[1..{idle}] OF CellPath;\n")
        idle_code = (f"FOR i := 1 TO {idle} DO\n"
                     f"    IdleConnects[i](CBT := IdleCobots[i], Execute := FALSE, IPAddress := '127.0.0.1', IPPort := 5889);\n"
                     f"    IdleSequences[i](CBT := IdleCobots[i], Segments := IdlePaths[i].Segments, Execute := FALSE);\n"
                     f"END_FOR;\n")
    return f"""(* bench/bench_scale.py: one controller, {robots} robot(s){f', {idle} idle FB sets' if idle else ''}. *)
TYPE CellPath : STRUCT Segments : ARRAY[0..5] OF {lib}\\stCBT_MovAbsParam; END_STRUCT; END_TYPE

PROGRAM Cell
VAR
    Execute : BOOL;
    Cobots : ARRAY[1..{robots}] OF {lib}\\stCBT_Connection;
    Connects : ARRAY[1..{robots}] OF {lib}\\CBT_Connect;
    Sequences : ARRAY[1..{robots}] OF {lib}\\PnP_Sequence;
    Paths : ARRAY[1..{robots}] OF CellPath;
    Run : ARRAY[1..{robots}] OF BOOL;
{idle_vars}    i : INT;
END_VAR
FOR i := 1 TO {robots} DO
    Connects[i](CBT := Cobots[i], Execute := Execute, IPAddress := '127.0.0.1', IPPort := INT_TO_UINT({BASE_PORT} + i));
    Run[i] := Execute AND (Run[i] OR Cobots[i].Connected);
    Sequences[i](CBT := Cobots[i], Segments := Paths[i].Segments, Execute := Run[i]);
END_FOR;
{idle_code}END_PROGRAM
"""


def load_cell(robots: int, idle: int = 0):
    import stvm
    with (V2 / "stvm.toml").open("rb") as fh:
        files = [V2 / name for name in tomllib.load(fh)["project"]["files"] if name not in DEMO_FILES]
    path = _HARNESS_DIR / f"cell_{robots}_{idle}.st"
    path.write_text(harness(robots, idle), encoding="utf-8")
    return stvm.load([str(f) for f in files] + [str(path)])


def _demo_targets() -> list[dict]:
    with SCENARIO.open("rb") as fh:
        demo = tomllib.load(fh)["set"]
    out = []
    for i in range(6):
        target = {k: demo[f"PnP_MoveParameters[{i}].TargetPosition.{k}"] for k in ("X", "Y", "Z", "RX", "RY", "RZ")}
        out.append({"Speed": demo[f"PnP_MoveParameters[{i}].Speed"],
                    "AccelTime": demo[f"PnP_MoveParameters[{i}].AccelTime"], "TargetPosition": target})
    return out


def start_cell(project, robots: int):
    """The VM and its lockstep transport: robot 0 answers any address (nothing reaches it), robot
    r at port BASE_PORT + r."""
    from stvm.lockstep import LockstepTransport
    transport = LockstepTransport()
    for r in range(1, robots + 1):
        transport.add_robot("127.0.0.1", BASE_PORT + r)
    vm = project.start(scan="1ms", transport=transport)
    transport.attach(vm)
    vm.collect_stats = False
    targets = _demo_targets()
    for r in range(1, robots + 1):
        for i, target in enumerate(targets):
            prefix = f"Cell.Paths[{r}].Segments[{i}]"
            vm.set(f"{prefix}.MovementCommand", "PTP")
            vm.set(f"{prefix}.DataFormat", "CPP_Abs")
            vm.set(f"{prefix}.Speed", target["Speed"])
            vm.set(f"{prefix}.AccelTime", target["AccelTime"])
            vm.set(f"{prefix}.PrecisePositioning", True)
            for k, v in target["TargetPosition"].items():
                vm.set(f"{prefix}.TargetPosition.{k}", v + (50.0 * ((r - 1) % 4) - 75.0 if k == "Y" else 0.0))
    vm.set("Cell.Execute", True)
    return vm, transport


def fb_instances(vm) -> int:
    """ST FB instances in the program tree (nested ones included; native FBs counted too)."""
    from stvm.semantics import types as t
    layouts = vm.layouts
    count = 0

    def visit_value(value, ty) -> None:
        nonlocal count
        if isinstance(ty, t.FBType):
            count += 1
            layout = layouts.of(ty)
            if layout is not None and value is not None:
                for slot in layout.owned():
                    visit_value(getattr(value, slot.storage, None), slot.type)
        elif isinstance(ty, t.ArrayType) and isinstance(ty.element, t.FBType) and value is not None:
            stack = [value]
            while stack:
                item = stack.pop()
                if isinstance(item, list):
                    stack.extend(item)
                else:
                    visit_value(item, ty.element)

    for _, inst, qual in vm.instances.values():
        for slot in layouts.pous[qual.lower()].owned():
            visit_value(getattr(inst, slot.storage, None), slot.type)
    return count


def measure_cell(robots: int, idle: int, warmup: int, scans: int) -> dict:
    project = load_cell(robots, idle)
    vm, transport = start_cell(project, robots)
    try:
        vm.run(cycles=warmup)
        connected = sum(bool(vm.get(f"Cell.Cobots[{r}].Connected")) for r in range(1, robots + 1))
        if connected != robots:
            raise RuntimeError(f"{robots} robot(s): only {connected} connected after {warmup} scans")
        # the lockstep hook timed apart: the rest of the scan is the ST program
        hooks = vm.on_scan_end
        index = hooks.index(transport.after_scan)
        lockstep = [0.0]
        clock = time.process_time

        def timed(v, hook=transport.after_scan):
            started = clock()
            hook(v)
            lockstep[0] += clock() - started
        hooks[index] = timed
        start_cycles = [vm.get(f"Cell.Sequences[{r}].Cycles") for r in range(1, robots + 1)]
        started = clock()
        vm.run(cycles=scans)
        total = clock() - started
        hooks[index] = transport.after_scan
        steps = sorted({vm.get(f"Cell.Sequences[{r}].Step") for r in range(1, robots + 1)})
        errors = [r for r in range(1, robots + 1) if vm.get(f"Cell.Sequences[{r}].Error")]
        if errors:
            raise RuntimeError(f"robot(s) {errors} ended in error")
        moved = sum(vm.get(f"Cell.Sequences[{r}].Cycles") - start_cycles[r - 1] for r in range(1, robots + 1))
        return {"robots": robots, "idle": idle, "fbs": fb_instances(vm), "scan_us": total / scans * 1e6,
                "lockstep_us": lockstep[0] / scans * 1e6, "st_us": (total - lockstep[0]) / scans * 1e6,
                "steps": steps, "cycles": moved}
    finally:
        vm.close()


def fit(xs: list[float], ys: list[float]) -> tuple[float, float, float]:
    """Least squares y = slope * x + intercept; (slope, intercept, R²)."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    slope = sxy / sxx if sxx else 0.0
    intercept = my - slope * mx
    ss_tot = sum((y - my) ** 2 for y in ys)
    ss_res = sum((y - (slope * x + intercept)) ** 2 for x, y in zip(xs, ys))
    return slope, intercept, (1.0 - ss_res / ss_tot) if ss_tot else 1.0


def measure(smoke: bool = False, scans: int = 4000, rounds: int = 2) -> tuple[list[dict], list[dict], float]:
    robots = (1, 2) if smoke else ROBOTS
    idle = (0, 2) if smoke else IDLE
    warmup = 300
    scans = 50 if smoke else scans
    rounds = 1 if smoke else rounds
    yard = for_loop_us()
    by_robots = []
    for n in robots:
        best = min((measure_cell(n, 0, warmup, scans) for _ in range(rounds)), key=lambda r: r["scan_us"])
        by_robots.append(best)
    by_size = []
    for k in idle:
        best = min((measure_cell(1, k, warmup, scans) for _ in range(rounds)), key=lambda r: r["scan_us"])
        by_size.append(best)
    yard = min(yard, for_loop_us())
    return by_robots, by_size, yard


def rows_of(by_robots: list[dict], by_size: list[dict], yard: float) -> list[Row]:
    rows = []
    for r in by_robots:
        rows.append(Row(f"scale: {r['robots']} robot(s) in lockstep, µs per scan", r["scan_us"], "µs", "FOR-100",
                        yard, "µs", "<= 100 µs at 16" if r["robots"] == 16 else "",
                        note=f"{r['fbs']} FB instances; ST {r['st_us']:.1f} µs, "
                             f"lockstep+emulators {r['lockstep_us']:.1f} µs"))
    slope, intercept, r2 = fit([r["robots"] for r in by_robots], [r["scan_us"] for r in by_robots])
    rows.append(Row("scale: growth per robot (least-squares slope)", slope, "µs", "FOR-100", yard, "µs", "linear",
                    note=f"intercept {intercept:.1f} µs, R² {r2:.4f}"))
    rows.append(Row("scale: R² of the linear fit against robots", r2, "", "a perfect straight line", 1.0, "",
                    "linear (≈ 1)"))
    slope_k, intercept_k, r2_k = fit([r["fbs"] for r in by_size], [r["scan_us"] for r in by_size])
    rows.append(Row("scale: growth per FB instance (1 robot, idle FBs added)", slope_k, "µs", "FOR-100", yard, "µs",
                    "linear", note=f"intercept {intercept_k:.1f} µs, R² {r2_k:.4f}, "
                                   f"{by_size[0]['fbs']}..{by_size[-1]['fbs']} FB instances"))
    return rows


def run(smoke: bool) -> list[Row]:
    """The registry's entry point (`python -m bench`)."""
    return rows_of(*measure(smoke))


def profile(robots: int, scans: int) -> None:
    """cProfile of the measured window (where the scan's time goes): the busiest functions, then
    the generated code's own time summed per POU (its class or function in the generated module,
    named by the POU it lowers) and the rest per Python module."""
    import bisect
    import cProfile
    import pstats
    from stvm.runtime.vm import GENERATED_FILENAME
    project = load_cell(robots)
    vm, _ = start_cell(project, robots)
    vm.run(cycles=300)
    profiler = cProfile.Profile()
    profiler.enable()
    vm.run(cycles=scans)
    profiler.disable()
    vm.close()
    stats = pstats.Stats(profiler)
    stats.sort_stats("tottime").print_stats(20)
    lines = project.lowered.source.splitlines()
    starts = [(i + 1, text.split()[1].split("(")[0].split(":")[0]) for i, text in enumerate(lines)
              if text.startswith(("class ", "def "))]
    keys = [s[0] for s in starts]
    names = {py: key for key, py in project.lowered.classes.items()}
    by_unit: dict[str, float] = {}
    for (file, line, _), (_, _, tottime, _, _) in stats.stats.items():   # type: ignore[attr-defined]
        if file == GENERATED_FILENAME:
            unit = starts[bisect.bisect_right(keys, line) - 1][1]
            label = "ST " + names.get(unit, unit)
        else:
            label = "Python " + file.replace(str(ROOT) + "/", "")
        by_unit[label] = by_unit.get(label, 0.0) + tottime
    total = sum(by_unit.values())
    print(f"own time per POU (generated code) and per Python file, {robots} robot(s), profiled "
          f"(cProfile inflates calls; shares, not µs, are the figure):")
    for label, spent in sorted(by_unit.items(), key=lambda kv: -kv[1])[:25]:
        print(f"  {spent / total * 100:5.1f} %  {spent / scans * 1e6:8.1f} µs/scan  {label}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="1 and 2 robots, a few scans (numbers mean nothing)")
    parser.add_argument("--scans", type=int, default=4000, help="measured scans per cell (after 300 warm-up scans)")
    parser.add_argument("--rounds", type=int, default=2, help="best of this many runs per cell")
    parser.add_argument("--profile", type=int, metavar="N", help="profile the cell of N robots instead")
    args = parser.parse_args()
    if args.profile:
        profile(args.profile, args.scans)
        return
    by_robots, by_size, yard = measure(args.smoke, args.scans, args.rounds)
    print(f"Python {sys.version.split()[0]}; CPU µs per scan (1 ms task), best of {args.rounds} runs; "
          f"yardstick: Python FOR-100 loop {yard:.2f} µs (same run)")
    print(f"{'robots':>6} {'FB inst.':>8} {'scan µs':>9} {'x FOR-100':>9} {'ST µs':>8} {'lockstep µs':>11} "
          f"{'PnP cycles':>10}  steps at the end")
    for r in by_robots:
        print(f"{r['robots']:6} {r['fbs']:8} {r['scan_us']:9.1f} {r['scan_us'] / yard:9.1f} {r['st_us']:8.1f} "
              f"{r['lockstep_us']:11.1f} {r['cycles']:10}  {r['steps']}")
    slope, intercept, r2 = fit([r["robots"] for r in by_robots], [r["scan_us"] for r in by_robots])
    print(f"fit against robots: {slope:.2f} µs per robot + {intercept:.2f} µs, R² = {r2:.4f}")
    print(f"\n1 robot, idle FB sets added (program size):\n{'idle sets':>9} {'FB inst.':>8} {'scan µs':>9} {'ST µs':>8}")
    for r in by_size:
        print(f"{r['idle']:9} {r['fbs']:8} {r['scan_us']:9.1f} {r['st_us']:8.1f}")
    slope_k, intercept_k, r2_k = fit([r["fbs"] for r in by_size], [r["scan_us"] for r in by_size])
    print(f"fit against FB instances: {slope_k:.3f} µs per FB instance + {intercept_k:.2f} µs, R² = {r2_k:.4f}")
    target = next((r for r in by_robots if r["robots"] == 16), None)
    if target is not None:
        print(f"16 robots: {target['scan_us']:.1f} µs per scan (target <= 100 µs: "
              f"{'met' if target['scan_us'] <= 100 else 'NOT met'})")


if __name__ == "__main__":
    main()
