"""Parser speed and large inputs (issue 16 item 3, issue 17's large-input target), side by side
with their yardsticks.

Run: python bench/bench_parser.py [--quick]        (blark: pip install -e '.[bench]')

Prints, each measured in this run (CPU time, best of a few runs, the stdlib parsed beforehand):
* parse and parse+check throughput (KiB/s) of stvm on st_src/ and on a generated dense
  10,000-line file, and of Lark's own parse+tree path (`parse_text_lark`, what stvm used before
  the fast driver) on the same text;
* blark's parse throughput (PyPI `blark`, an Earley parser for TwinCAT ST) on the same files:
  st_src files blark can parse, and a generated dense 1,000-line file (blark takes about a
  second per KiB), with the ratio stvm parse+check / blark parse;
* a generated 100,000-line file in a fresh subprocess (no cache): parse+check alone
  (`stvm.project.check`), and `stvm check` (which also lowers and compiles the generated
  Python): wall and CPU time and peak RSS.
Targets: dense parse+check >= 400 KiB/s; parse+check >= 50x blark's parse; 100k lines checked in
<= 10 s and <= 400 MB.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from bench_large import generate  # noqa: E402  (the FB-per-block generator of bench_large.py)

from stvm.project import check, stdlib_units  # noqa: E402
from stvm.settings import DEFAULT_SETTINGS  # noqa: E402
from stvm.syntax.parser import _parser, parse_text, parse_text_lark  # noqa: E402

PROJECTS = ["st_src", "st_src/cbt_v2", "st_src/kuka", "st_src/rockwell"]   # each a project (stvm.toml)


def cpu(fn, repeat: int = 5) -> float:
    """Best CPU seconds of `repeat` calls (CPU time: the machine is shared)."""
    best = float("inf")
    for _ in range(repeat):
        gc.collect()
        start = time.process_time()
        fn()
        best = min(best, time.process_time() - start)
    return best


def kib(paths) -> float:
    return sum(p.stat().st_size for p in paths) / 1024


def parse_all(paths, parse=parse_text):
    for p in paths:
        parse(p.read_text(encoding="utf-8"), str(p))


def blark_parse(paths):
    """blark's parse of each file: (KiB parsed, CPU s, files parsed, failed names), or None."""
    try:
        from blark.parse import get_parser, parse_source_code
    except ImportError:
        return None
    get_parser()
    size = seconds = 0.0
    ok, failed = 0, []
    for p in paths:
        text = p.read_text(encoding="utf-8")
        start = time.process_time()
        result = parse_source_code(text, fn=str(p))
        elapsed = time.process_time() - start
        if result.exception is None:
            size += len(text.encode()) / 1024
            seconds += elapsed
            ok += 1
        else:
            failed.append(p)
    return size, seconds, ok, failed


FRONT_END = """
import sys
from stvm.project import check
analysis, diags, _ = check([sys.argv[1]], use_cache=False)
sys.exit(1 if analysis is None else 0)
"""


def big_check(lines: int, folder: Path, front_end_only: bool = False) -> tuple[float, float, float, int, str]:
    """`stvm check` (parse, check, then lower and compile the generated Python) or only the
    front end (`stvm.project.check`: parse and check) of a generated file, in a fresh process."""
    big = folder / "big.st"
    n = generate(lines, big) if not big.exists() else big.read_text().count("\n")
    command = [sys.executable, "-c", FRONT_END, str(big)] if front_end_only else \
        [sys.executable, "-m", "stvm", "check", str(big)]
    code = ("import resource, subprocess, sys, time; t = time.perf_counter(); "
            "p = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
            "r = resource.getrusage(resource.RUSAGE_CHILDREN); "
            "print(time.perf_counter() - t, r.ru_utime + r.ru_stime, r.ru_maxrss / 1024, p.returncode); "
            "sys.stderr.write(p.stderr[-300:])")
    # an empty cache folder of its own per command: each run is cold
    env = dict(os.environ, STVM_CACHE_DIR=str(folder / ("cache-front-end" if front_end_only else "cache-check")))
    out = subprocess.run([sys.executable, "-c", code, *command], capture_output=True, text=True, cwd=ROOT, env=env)
    wall, cpu_s, rss, rc = out.stdout.split()
    return float(wall), float(cpu_s), float(rss), int(rc), f"{n:,} lines, {big.stat().st_size / 2**20:.1f} MiB"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip blark and the 100k-line check")
    ap.add_argument("--lines", type=int, default=100_000, help="lines of the large input (default 100,000)")
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"load {os.getloadavg()[0]:.1f}; figures are CPU time, best of 5")
    _parser()
    stdlib_units(DEFAULT_SETTINGS)
    folder = Path(tempfile.mkdtemp(prefix="stvm-bench-parser-"))
    dense = folder / "dense10k.st"
    generate(10_000, dense)
    small = folder / "dense1k.st"
    generate(1_000, small)

    st_files = sorted((ROOT / "st_src").rglob("*.st"))
    clean = [p for p in st_files if not parse_text(p.read_text(encoding="utf-8"), str(p))[1]]
    project_files = [p for proj in PROJECTS for p in sorted((ROOT / proj).glob("*.st"))]

    rows = []
    for label, files in ((f"st_src ({len(clean)} files that parse)", clean), ("dense 10k lines", [dense]),
                         ("dense 1k lines", [small])):
        size = kib(files)
        t_parse = cpu(lambda: parse_all(files))
        t_lark = cpu(lambda: parse_all(files, parse_text_lark))
        rows.append((label, size, t_parse, t_lark))
    t_check_st = cpu(lambda: [check([ROOT / proj], use_cache=False) for proj in PROJECTS])
    t_check_dense = cpu(lambda: check([dense], use_cache=False))
    t_check_small = cpu(lambda: check([small], use_cache=False))

    print(f"\n{'input':34} {'KiB':>7} {'parse':>11} {'Lark path':>11} {'speed-up':>9}")
    for label, size, t_parse, t_lark in rows:
        print(f"{label:34} {size:7.0f} {size / t_parse:7.0f} KiB/s {size / t_lark:5.0f} KiB/s {t_lark / t_parse:8.1f}x")
    st_kib, dense_kib, small_kib = kib(project_files), kib([dense]), kib([small])
    print("\nparse+check (stvm.project.check, no cache, stdlib memoised):")
    print(f"  st_src projects {', '.join(p.split('/')[-1] for p in PROJECTS)} ({st_kib:.0f} KiB): "
          f"{st_kib / t_check_st:.0f} KiB/s")
    print(f"  dense 10k lines ({dense_kib:.0f} KiB): {dense_kib / t_check_dense:.0f} KiB/s   (target >= 400)")
    print(f"  dense 1k lines ({small_kib:.0f} KiB): {small_kib / t_check_small:.0f} KiB/s")

    if args.quick:
        return
    blark_st = blark_parse(st_files)
    if blark_st is None:
        print("\nblark not installed (pip install -e '.[bench]'): no yardstick")
    else:
        size, seconds, ok, failed = blark_st
        same = [p for p in st_files if p not in failed]
        t_same = cpu(lambda: parse_all(same))
        print("\nblark 0.8.3 parse (Earley), same files:")
        print(f"  st_src: parses {ok} of {len(st_files)} files (the rest use Sysmac namespaces, `\\` paths, OO): "
              f"{size:.0f} KiB at {size / seconds:.1f} KiB/s; stvm parse of those files {size / t_same:.0f} KiB/s "
              f"({seconds / t_same:.0f}x); stvm parse+check of the st_src projects {st_kib / t_check_st:.0f} KiB/s "
              f"= {st_kib / t_check_st / (size / seconds):.0f}x blark's parse   (target >= 50x)")
        size, seconds, ok, failed = blark_parse([small])
        if ok:
            print(f"  dense 1k lines: blark {size / seconds:.2f} KiB/s; stvm parse {small_kib / rows[2][2]:.0f} KiB/s "
                  f"({seconds / rows[2][2]:.0f}x), parse+check {small_kib / t_check_small:.0f} KiB/s "
                  f"= {small_kib / t_check_small / (size / seconds):.0f}x blark's parse   (target >= 50x)")
        else:
            print("  dense 1k lines: blark failed to parse it")

    wall, cpu_s, rss, rc, what = big_check(args.lines, folder, front_end_only=True)
    print(f"\nlarge input, generated {what}, each in a fresh process (no cache):   (target <= 10 s, <= 400 MB)")
    print(f"  parse + check (stvm.project.check):  {wall:5.1f} s wall, {cpu_s:5.1f} s CPU, peak RSS {rss:5.0f} MB, exit {rc}")
    wall, cpu_s, rss, rc, what = big_check(args.lines, folder)
    print(f"  `stvm check` (+ lower and compile):  {wall:5.1f} s wall, {cpu_s:5.1f} s CPU, peak RSS {rss:5.0f} MB, exit {rc}")


if __name__ == "__main__":
    main()
