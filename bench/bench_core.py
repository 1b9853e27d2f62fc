"""Core benchmarks (issue 3): generated code vs hand-written Python, parse/check speed, load time.

Run: python bench/bench_core.py   (prints a table; no timed assertions anywhere)

* Programs: a BOOL toggle, a 100-iteration FOR sum with INT wrap, a worst-case bubble sort of
  1000 DINT. Each is timed as the ST program body (the generated `__call__`) and as a whole
  `vm.scan()` (task dispatch included), against a hand-written Python class doing the same work
  with the same semantics (INT wrap-around where ST wraps).
* Parse + check throughput in KiB/s over the thesis sources and a generated 1,000-line file set.
* Load time of that file set: cold (a fresh process, empty compile cache), cached (a fresh
  process, warm cache) and repeated in one process.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import stvm  # noqa: E402
from stvm.project import check  # noqa: E402

ST = ROOT / "bench" / "st"


class HandToggle:
    def __init__(self):
        self.flag = False

    def __call__(self):
        self.flag = not self.flag


class HandForSum:
    def __init__(self):
        self.i = 0
        self.total = 0

    def __call__(self):
        total = self.total
        for i in range(1, 101):
            total = ((total + i * 7 + 32768) & 0xFFFF) - 32768   # INT wrap, as ST does
        self.total = total
        self.i = 101


class HandBubble:
    def __init__(self):
        self.data = [0] * 1000

    def __call__(self):
        data = self.data
        for i in range(1000):
            data[i] = 999 - i
        for i in range(1, 1000):
            for j in range(1000 - i):
                if data[j] > data[j + 1]:
                    data[j], data[j + 1] = data[j + 1], data[j]


def best_of(fn, repeat: int, number: int) -> float:
    """Best mean seconds per call over `repeat` rounds of `number` calls."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - start) / number)
    return min(times)


def bench_programs() -> None:
    cases = [("BOOL toggle", "bool_toggle.st", HandToggle, 20, 20000),
             ("FOR sum 100 (INT wrap)", "for_sum.st", HandForSum, 10, 2000),
             ("bubble sort 1000 DINT", "bubble_sort.st", HandBubble, 5, 1)]
    print(f"{'program':28} {'hand µs':>10} {'stvm body µs':>13} {'ratio':>6} {'vm.scan µs':>11} {'ratio':>6}")
    for label, file, hand_cls, repeat, number in cases:
        project = stvm.load([ST / file], use_cache=False)
        vm = project.start(scan="1ms")
        vm.collect_stats = False
        body = next(iter(vm.instances.values()))[1]
        hand = hand_cls()
        t_hand = best_of(hand, repeat, number)
        t_body = best_of(body, repeat, number)
        t_scan = best_of(vm.scan, repeat, number)
        print(f"{label:28} {t_hand * 1e6:10.2f} {t_body * 1e6:13.2f} {t_body / t_hand:6.2f} {t_scan * 1e6:11.2f} {t_scan / t_hand:6.2f}")


SYNTH_FB = """
FUNCTION_BLOCK Synth{n}
VAR_INPUT
    Execute : BOOL;
    Target : REAL;
    Limit : INT := {n};
END_VAR
VAR_OUTPUT
    Done : BOOL;
    Busy : BOOL;
    Count : DINT;
    Text : STRING[40];
END_VAR
VAR
    Edge : R_TRIG;
    Step : INT;
    Acc : REAL;
    Hist : ARRAY[0..9] OF REAL;
    k : INT;
END_VAR
Edge(CLK := Execute);
IF Edge.Q THEN
    Busy := TRUE;
    Step := 10;
END_IF;
CASE Step OF
    10:
        Acc := 0.0;
        FOR k := 0 TO 9 DO
            Hist[k] := Target * INT_TO_REAL(k);
            Acc := Acc + Hist[k];
        END_FOR;
        Step := 20;
    20:
        IF Acc > Target THEN
            Count := Count + 1;
            Step := 30;
        ELSIF Count < Limit THEN
            Count := Count + 2;
        ELSE
            Step := 30;
        END_IF;
    30:
        Text := CONCAT('done ', DINT_TO_STRING(Count));
        Done := TRUE;
        Busy := FALSE;
        Step := 0;
ELSE
    Done := FALSE;
END_CASE;
END_FUNCTION_BLOCK
"""


def synth_files(folder: Path, files: int = 10) -> list[Path]:
    paths = []
    for f in range(files):
        text = "".join(SYNTH_FB.format(n=f * 10 + k) for k in range(2))
        path = folder / f"synth_{f}.st"
        path.write_text(text)
        paths.append(path)
    main = folder / "main.st"
    body = "".join(f"    fb{i}(Execute := run, Target := 1.5);\n" for i in range(20))
    decls = "".join(f"    fb{i} : Synth{(i // 2) * 10 + i % 2};\n" for i in range(20))
    main.write_text(f"PROGRAM Main\nVAR\n    run : BOOL;\n{decls}END_VAR\nrun := NOT run;\n{body}END_PROGRAM\n")
    paths.append(main)
    return paths


def bench_front_end() -> None:
    folder = Path(tempfile.mkdtemp(prefix="stvm-bench-"))
    try:
        paths = synth_files(folder)
        lines = sum(len(p.read_text().splitlines()) for p in paths)
        thesis = sorted((ROOT / "st_src").glob("*.st"))
        for label, files in (("synthetic", paths), ("thesis st_src", thesis)):
            if not files:
                continue
            size_kib = sum(p.stat().st_size for p in files) / 1024
            times = []
            for _ in range(3):
                start = time.perf_counter()
                analysis, diags, _ = check(files)
                times.append(time.perf_counter() - start)
            errors = [d for d in diags if d.is_error]
            print(f"parse+check {label}: {size_kib:.1f} KiB in {min(times) * 1000:.1f} ms = "
                  f"{size_kib / min(times):.0f} KiB/s (incl. the stdlib){'  [has errors]' if errors else ''}")
        bench_load(folder, paths, lines)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# One load in a fresh interpreter: what `stvm run` pays. Prints the seconds spent importing stvm's
# driver and in `load` itself, as JSON; the parent adds the process's whole wall time.
_CHILD = """
import json, sys, time
start = time.perf_counter()
from stvm.project import load
imported = time.perf_counter()
project = load(sys.argv[1:])
loaded = time.perf_counter()
print(json.dumps({"import": imported - start, "load": loaded - imported, "from_cache": project.from_cache}))
"""


def _load_in_fresh_process(paths: list[Path], env: dict[str, str]) -> tuple[float, dict]:
    start = time.perf_counter()
    result = subprocess.run([sys.executable, "-c", _CHILD, *map(str, paths)], env=env, cwd=ROOT,
                            capture_output=True, text=True, check=True)
    return time.perf_counter() - start, json.loads(result.stdout.splitlines()[-1])


def bench_load(folder: Path, paths: list[Path], lines: int, runs: int = 3) -> None:
    """Cold: a fresh process with an empty compile cache (nothing parsed, nothing imported);
    cached: a fresh process whose cache holds the project; then a repeated load in this process."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
               STVM_CACHE_DIR=str(folder / "cache"), STVM_CACHE_KEY_FILE=str(folder / "key" / "cache.key"))
    figures: dict[str, list[tuple[float, dict]]] = {"cold": [], "cached": []}
    for _ in range(runs):
        shutil.rmtree(folder / "cache", ignore_errors=True)
        figures["cold"].append(_load_in_fresh_process(paths, env))
        figures["cached"].append(_load_in_fresh_process(paths, env))
    assert not any(child["from_cache"] for _, child in figures["cold"]), "the cold load found a cache"
    assert all(child["from_cache"] for _, child in figures["cached"]), "the cached load missed the cache"
    for label, runs_of in figures.items():
        whole = statistics.median(total for total, _ in runs_of)
        imports = statistics.median(child["import"] for _, child in runs_of)
        load_s = statistics.median(child["load"] for _, child in runs_of)
        print(f"load of {lines} lines in {len(paths)} files, {label}, fresh process: {whole * 1000:.0f} ms in all "
              f"(import of stvm.project {imports * 1000:.0f} ms, load {load_s * 1000:.0f} ms, the rest Python's "
              f"own start-up; median of {runs})")
    os.environ["STVM_CACHE_DIR"] = str(folder / "cache")
    os.environ["STVM_CACHE_KEY_FILE"] = str(folder / "key" / "cache.key")
    stvm.load(paths)
    again = []
    for _ in range(runs):
        start = time.perf_counter()
        stvm.load(paths)
        again.append(time.perf_counter() - start)
    print(f"load of {lines} lines again in the same process: {statistics.median(again) * 1000:.0f} ms "
          f"(median of {runs})")


if __name__ == "__main__":
    bench_programs()
    bench_front_end()
