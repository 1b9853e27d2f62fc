"""Core benchmarks (issue 3): generated code vs hand-written Python, parse/check speed, load time.

Run: python bench/bench_core.py   (prints a table; no timed assertions anywhere)

* Programs: a BOOL toggle, a 100-iteration FOR sum with INT wrap, a worst-case bubble sort of
  1000 DINT. Each is timed as the ST program body (the generated `__call__`) and as a whole
  `vm.scan()` (task dispatch included), against a hand-written Python class doing the same work
  with the same semantics (INT wrap-around where ST wraps).
* Parse + check throughput in KiB/s over the thesis sources and a generated 1,000-line file set.
* Cold and cached load time of that file set.
"""

from __future__ import annotations

import os
import shutil
import statistics
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
        cache = folder / "cache"
        os.environ["STVM_CACHE_DIR"] = str(cache)
        colds, warms = [], []
        for _ in range(3):
            shutil.rmtree(cache, ignore_errors=True)
            start = time.perf_counter()
            stvm.load(paths)
            colds.append(time.perf_counter() - start)
            start = time.perf_counter()
            stvm.load(paths)
            warms.append(time.perf_counter() - start)
        print(f"load of {lines} lines in {len(paths)} files: cold {statistics.median(colds) * 1000:.0f} ms, "
              f"cached {statistics.median(warms) * 1000:.0f} ms (median of 3, in-process)")
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    bench_programs()
    bench_front_end()
