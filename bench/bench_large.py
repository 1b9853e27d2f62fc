"""Large inputs (issue 17): first load of a generated 100,000-line program, where the time and
memory go, and `stvm check` of an oversized file.

Run: nice python bench/bench_large.py [--lines 100000] [--repeat 3]

Each figure is measured in fresh processes (`/usr/bin/time`-like: wall time, CPU time and peak
RSS from `resource`; min / median of `--repeat`), with the compile cache off (`--no-cache`) and
with a new, empty cache folder (what a first `stvm run` does: Lark's tables built, the
compiled project pickled and written; a one-file project writes no unit entry), next to a yardstick measured in the same run:
the same program at a tenth of the size (the ratio shows whether the cost grows linearly). On a
shared machine the CPU time is the steadier figure.
Phases (one process, the steps of `project.load`): read, parse to nodes (the fast LALR driver, no
Lark tree), check, lower + compile, the project (native modules), the
load's cache entry, instances, one scan; each with the time spent in the cyclic collector.
Targets: <= 10 s and <= 400 MB for the 100,000-line first load.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

FB = """FUNCTION_BLOCK FB{i}
VAR_INPUT en : BOOL; x : INT; END_VAR
VAR_OUTPUT y : DINT; done : BOOL; END_VAR
VAR k : INT; acc : DINT; arr : ARRAY[0..9] OF INT; s : STRING[20]; t : TON; END_VAR
(* block {i}: accumulate, then pick an output by case *)
IF en THEN
    acc := acc + x * {m};
    FOR k := 0 TO 9 DO
        arr[k] := arr[k] + k;
    END_FOR;
ELSIF x > {c} THEN
    acc := acc - 1;
ELSE
    acc := 0;
END_IF;
CASE x MOD 4 OF
    0: y := acc;
    1: y := acc * 2;
    2: y := acc / 3;
ELSE
    y := -acc;
END_CASE;
t(IN := en, PT := T#{p}ms);
done := t.Q AND (y > 10);
s := CONCAT('fb', INT_TO_STRING(x));
END_FUNCTION_BLOCK
"""


def generate(lines: int, path: Path) -> int:
    blocks, count, i = [], 0, 0
    while count < lines - 10:
        block = FB.format(i=i, m=i % 7 + 1, c=i % 100, p=i % 50 + 1)
        blocks.append(block)
        count += block.count("\n")
        i += 1
    main = ["PROGRAM Main", "VAR"] + [f"  f{j} : FB{j};" for j in range(i)] + ["  c : INT;", "END_VAR", "c := c + 1;"]
    main += [f"f{j}(en := c MOD 2 = 0, x := c);" for j in range(i)] + ["END_PROGRAM"]
    text = "".join(blocks) + "\n".join(main) + "\n"
    path.write_text(text)
    return text.count("\n")


PHASES = textwrap.dedent("""
    import gc, resource, sys, time
    from pathlib import Path
    t0, c0 = time.perf_counter(), time.process_time()
    collector = [0.0, 0, 0.0]   # seconds inside the cyclic collector, collections, start of the current one
    def on_gc(phase, info):
        if phase == "start":
            collector[2] = time.perf_counter()
        else:
            collector[0] += time.perf_counter() - collector[2]
            collector[1] += 1
    gc.callbacks.append(on_gc)
    import stvm.project as P
    from stvm.settings import DEFAULT_SETTINGS as S
    from stvm.syntax.parser import _parser, _driver
    from stvm.semantics import analyze
    from stvm.stdlib import NATIVE_FUNCTIONS
    _parser(); _driver("start"); P.stdlib_units(S)
    def rss(): return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    marks, last = [], [t0, c0, 0.0]
    def mark(name):
        wall, cpu = time.perf_counter(), time.process_time()
        marks.append((name, wall - last[0], cpu - last[1], collector[0] - last[2], rss()))
        last[:] = [wall, cpu, collector[0]]
    mark("imports + grammar + stdlib")
    # the steps of project.load, one by one (the collector paused where load pauses it)
    texts, _ = P.read_files([Path(sys.argv[1])]); mark("read")
    with P._collector_paused():
        unit, diags = P.parse_unit(texts[0][0], texts[0][1], S, False); mark("parse to nodes")
        # no unit cache entry: the load of a one-file project writes none (project.load)
        units, _, sources = P.stdlib_units(S)
        analysis = analyze(list(units) + [unit], S, NATIVE_FUNCTIONS); mark("check")
        del unit
    model, handed_over = analysis.model, [analysis]
    del analysis
    from stvm.lower import lower_project
    from stvm.lower.product import compile_module
    from stvm.runtime.vm import GENERATED_FILENAME
    with P._collector_paused():   # as P._lower_and_compile, in two steps
        lowered = lower_project(handed_over.pop(), S); mark("lower")
        code = compile_module(lowered.source, GENERATED_FILENAME); mark("compile (Python's compile())")
    project = P.Project(model, lowered, code, dict(texts), S, [], False, {}, None, P._native_modules(lowered))
    mark("project (native modules)")
    if "--cache" in sys.argv:
        import marshal, pickle
        with P._collector_paused():
            pickle.dumps((model, lowered, [], marshal.dumps(code), dict(texts), project.native_modules),
                         protocol=pickle.HIGHEST_PROTOCOL)
        mark("load cache entry (pickle)")
    vm = project.start(scan=10_000_000); mark("instances (project.start)")
    vm.scan(); mark("1 scan")
    for name, wall, cpu, in_gc, peak in marks:
        print(f"  {name:28} {wall:6.2f} s  cpu {cpu:6.2f} s  collector {in_gc:5.2f} s  peak RSS {peak:4.0f} MB")
    print(f"  {'total':28} {time.perf_counter() - t0:6.2f} s  cpu {time.process_time() - c0:6.2f} s  "
          f"collector {collector[0]:5.2f} s ({collector[1]} runs); generated Python {len(lowered.source) / 2**20:.1f} MiB")
""")


def timed(argv: list[str], env: dict | None = None) -> tuple[float, float, float, int, str]:
    """(wall s, CPU s (user + sys), peak RSS MB, exit code, stderr tail) of one fresh process."""
    code = ("import resource, subprocess, sys, time; t = time.perf_counter(); "
            "p = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
            "r = resource.getrusage(resource.RUSAGE_CHILDREN); "
            "print(time.perf_counter() - t, r.ru_utime + r.ru_stime, r.ru_maxrss / 1024, p.returncode); "
            "sys.stderr.write(p.stderr[-400:])")
    result = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, cwd=ROOT,
                            env={**os.environ, **(env or {})})
    seconds, cpu, megabytes, rc = result.stdout.split()
    return float(seconds), float(cpu), float(megabytes), int(rc), result.stderr


def repeated(argv: list[str], times: int, fresh_cache: bool = False) -> str:
    """min / median of wall, CPU and peak RSS over `times` fresh processes (each with a new, empty
    cache folder when `fresh_cache`: the Lark tables are built and every cache entry written)."""
    runs = []
    for _ in range(times):
        env = {"STVM_CACHE_DIR": tempfile.mkdtemp(prefix="stvm-large-cache-")} if fresh_cache else None
        wall, cpu, peak, rc, err = timed(argv, env)
        if rc != 0:
            raise SystemExit(f"{' '.join(argv)}: exit {rc}\n{err}")
        runs.append((wall, cpu, peak))
    walls, cpus, peaks = (sorted(col) for col in zip(*runs))
    return (f"{min(walls):5.1f} / {statistics.median(walls):5.1f} s wall, {min(cpus):5.1f} / "
            f"{statistics.median(cpus):5.1f} s CPU, {min(peaks):4.0f} / {statistics.median(peaks):4.0f} MB")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lines", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=1, help="fresh processes per figure (min / median)")
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="stvm-large-"))
    env_note = f"load {os.getloadavg()[0]:.2f}"
    big, small = work / "big.st", work / "small.st"
    n_big, n_small = generate(args.lines, big), generate(args.lines // 10, small)
    print(f"large input: {n_big:,} lines ({big.stat().st_size / 2**20:.1f} MiB), yardstick {n_small:,} lines; "
          f"{env_note}; min / median of {args.repeat}")
    run = [sys.executable, "-m", "stvm", "run", "--cycles", "1"]
    print(f"  yardstick, --no-cache        {repeated(run + ['--no-cache', str(small)], args.repeat)}")
    print(f"  first load + 1 scan, --no-cache  {repeated(run + ['--no-cache', str(big)], args.repeat)}")
    print(f"  yardstick, empty cache       {repeated(run + [str(small)], args.repeat, fresh_cache=True)}")
    print(f"  first load + 1 scan, empty cache {repeated(run + [str(big)], args.repeat, fresh_cache=True)}")
    print("where it goes (one process, the steps of project.load, collector paused as there; "
          "with the load's cache entry pickled, not written):")
    subprocess.run([sys.executable, "-c", PHASES, str(big), "--cache"], cwd=ROOT)
    huge = work / "huge.st"
    with huge.open("w") as fh:
        while fh.tell() < 9 * 2**20:
            fh.write(FB.format(i=fh.tell(), m=1, c=1, p=1))
    s_huge, _, m_huge, rc_huge, err_huge = timed([sys.executable, "-m", "stvm", "check", str(huge)])
    print(f"stvm check of a 9 MiB file: {s_huge:.2f} s, {m_huge:.0f} MB, rc {rc_huge}: {err_huge.strip().splitlines()[0]}")


if __name__ == "__main__":
    main()
