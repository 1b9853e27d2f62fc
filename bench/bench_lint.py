"""Lint speed: the thesis sources (warm parse cache) and generated programs of 10k/25k/50k lines.

    python bench/bench_lint.py [--sizes 10000,25000,50000] [--runs 3]

Prints, with the load average: the time of `stvm lint st_src/` with a warm parse cache (target
< 1 s on one core), split into load (cached trees + checker) and lint analysis; the same for
each generated program (target: 50,000 lines < 15 s, linear: the time per 1,000 lines should
stay flat), and as a yardstick measured in the same run the checker (`semantics.analyze`) on the
same trees, so figures taken on a busy machine can be compared by ratio. Times are CPU seconds
of the process (one core), which a busy machine inflates much less than wall time.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from stvm.lint import lint_analysis, select_rules  # noqa: E402
from stvm.project import check_project as load_for_lint  # noqa: E402 (the driver's parse + check)
from stvm.settings import DEFAULT_SETTINGS  # noqa: E402

FB_TEMPLATE = """
FUNCTION_BLOCK Station{i}
VAR_INPUT
    Execute : BOOL;
    Target : ARRAY[0..5] OF REAL;
    Count : INT(0..50);
END_VAR
VAR_OUTPUT
    Done, Busy, Error : BOOL;
    ErrorID : WORD;
    Text : STRING[200];
END_VAR
VAR
    start : R_TRIG;
    timer : TON;
    step : INT;
    data : ARRAY[0..63] OF INT;
    total, k, guard : INT;
    part : STRING[40];
    scale : DINT;
END_VAR
start(CLK := Execute);
IF start.Q THEN
    step := 10;
    Busy := TRUE;
    Done := FALSE;
    Error := FALSE;
END_IF;
CASE step OF
    0:  Busy := FALSE;
    10: total := 0;
        FOR k := 0 TO Count DO
            total := total + data[k];
        END_FOR;
        step := 20;
    20: part := RealToFormatString(In := Target[0], Exponent := FALSE, Sign := TRUE, MinLen := 1, DecPlace := 2);
        Text := CONCAT('MOVE(', part, ')');
        IF total > 1000 THEN
            step := 30;
        ELSIF total < 0 THEN
            Error := TRUE;
            ErrorID := 16#{i:04X};
            step := 0;
        ELSE
            step := 40;
        END_IF;
    30: scale := INT_TO_DINT(total) * 1000;
        IF scale > 100000 THEN
            step := 40;
        END_IF;
    40: timer(IN := TRUE, PT := T#100ms);
        IF timer.Q THEN
            timer(IN := FALSE);
            Done := TRUE;
            Busy := FALSE;
            step := 0;
        END_IF;
END_CASE;
IF NOT Execute AND NOT Busy THEN
    Done := FALSE;
    Error := FALSE;
END_IF;
guard := guard + 1;
IF guard > 30000 THEN
    guard := 0;
END_IF;
END_FUNCTION_BLOCK
"""


def generate(lines: int) -> str:
    per_fb = FB_TEMPLATE.count("\n")
    count = max(1, lines // (per_fb + 3))
    parts = [FB_TEMPLATE.format(i=i) for i in range(count)]
    calls = "\n".join(f"s{i}(Execute := go, Count := 10);" for i in range(count))
    decls = "\n".join(f"    s{i} : Station{i};" for i in range(count))
    parts.append(f"PROGRAM Main\nVAR\n    go : BOOL;\n{decls}\nEND_VAR\n{calls}\nEND_PROGRAM\n")
    return "".join(parts)


def measure(paths, runs: int) -> dict:
    """Best of `runs`: CPU seconds of this process (time.process_time: what one core spends,
    whatever the other processes on the machine do) for load, lint and the checker."""
    settings = DEFAULT_SETTINGS
    rules = select_rules()
    best = None
    for _ in range(runs):
        t0 = time.process_time()
        loaded = load_for_lint(paths, settings)
        t1 = time.process_time()
        findings = lint_analysis(loaded.analysis, settings, rules, files=set(loaded.parsed.files))
        t2 = time.process_time()
        from stvm.semantics import analyze
        units = []
        from stvm.project import parse_unit, stdlib_units
        units += stdlib_units(settings)[0]
        for f in loaded.parsed.files:
            units.append(parse_unit(f, loaded.sources[f], settings)[0])
        t3 = time.process_time()
        analyze(units, settings)
        t4 = time.process_time()
        row = {"load": t1 - t0, "lint": t2 - t1, "total": t2 - t0, "check": t4 - t3, "findings": len(findings)}
        if best is None or row["total"] < best["total"]:
            best = row
    return best


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="10000,25000,50000")
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args(argv)
    os.environ.setdefault("STVM_CACHE_DIR", tempfile.mkdtemp(prefix="stvm-bench-lint-"))
    print(f"load average: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f} "
          f"(2 cores shared; CPU seconds, best of {args.runs})")
    load_for_lint([ROOT / "st_src"], DEFAULT_SETTINGS)   # warm the parse cache
    row = measure([ROOT / "st_src"], args.runs)
    print(f"st_src (4,200 lines, warm cache, in process): total {row['total']:.2f} s = load {row['load']:.2f} s "
          f"+ lint {row['lint']:.2f} s; yardstick checker {row['check']:.2f} s; "
          f"lint/checker {row['lint'] / row['check']:.1f}x; {row['findings']} findings  (target total < 1 s)")
    work = Path(tempfile.mkdtemp(prefix="stvm-bench-lint-src-"))
    per_k = []
    print(f"{'lines':>7} {'parse (cold)':>12} {'load':>6} {'lint':>6} {'total':>6} {'checker':>8} "
          f"{'lint/checker':>12} {'lint s/1k lines':>15}")
    for size in [int(s) for s in args.sizes.split(",")]:
        path = work / f"gen{size}.st"
        text = generate(size)
        path.write_text(text)
        lines = text.count("\n")
        t = time.process_time()
        load_for_lint([path], DEFAULT_SETTINGS)
        cold = time.process_time() - t
        row = measure([path], args.runs)
        per_k.append(row["lint"] / lines * 1000)
        print(f"{lines:>7} {cold:>11.1f}s {row['load']:>5.1f}s {row['lint']:>5.1f}s {row['total']:>5.1f}s "
              f"{row['check']:>7.1f}s {row['lint'] / row['check']:>11.1f}x {per_k[-1]:>15.3f}")
    if len(per_k) > 1:
        print(f"scaling: lint time per 1k lines, largest / smallest program = {per_k[-1] / per_k[0]:.2f} "
              f"(1.0 = linear); target 50k lines total < 15 s (warm)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
