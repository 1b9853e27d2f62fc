"""Large inputs (issue 17): first load of a generated 100,000-line program, where the time and
memory go, and `stvm check` of an oversized file.

Run: python bench/bench_large.py [--lines 100000]

Each figure is measured in a fresh process (`/usr/bin/time`-like: wall time and peak RSS from
`resource`), with the compile cache off, next to a yardstick measured in the same run: the
same program at a tenth of the size (the ratio shows whether the cost grows linearly).
Phases (one process): read, parse to nodes (the fast LALR driver, no Lark tree), check, lower, compile.
Targets: <= 10 s and <= 400 MB for the 100,000-line first load.
"""

from __future__ import annotations

import argparse
import os
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
    import resource, sys, time
    from pathlib import Path
    t0 = time.perf_counter()
    from stvm.project import read_files, stdlib_units, _lower_and_compile, _collector_paused
    from stvm.settings import DEFAULT_SETTINGS as S
    from stvm.syntax.parser import _parser, _ToNodes, parse_text
    from stvm.semantics import analyze
    _parser(); stdlib_units(S)
    def rss(): return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    marks = [("imports + grammar + stdlib", time.perf_counter() - t0, rss())]
    def mark(name, start): marks.append((name, time.perf_counter() - start, rss()))
    with _collector_paused():
        t = time.perf_counter(); texts, _ = read_files([Path(sys.argv[1])]); mark("read", t)
        t = time.perf_counter(); unit, d = parse_text(texts[0][1], texts[0][0]); mark("parse to nodes", t)
        units, _, sources = stdlib_units(S)
        t = time.perf_counter(); analysis = analyze(list(units) + [unit], S); mark("check", t)
    t = time.perf_counter(); _lower_and_compile(analysis, S, texts, dict(texts)); mark("lower + compile", t)
    for name, seconds, peak in marks:
        print(f"  {name:28} {seconds:7.2f} s   peak RSS {peak:7.0f} MB")
""")


def timed(argv: list[str]) -> tuple[float, float, int, str]:
    code = ("import resource, subprocess, sys, time; t = time.perf_counter(); "
            "p = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
            "r = resource.getrusage(resource.RUSAGE_CHILDREN); "
            "print(time.perf_counter() - t, r.ru_maxrss / 1024, p.returncode); sys.stderr.write(p.stderr[-400:])")
    result = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, cwd=ROOT)
    seconds, megabytes, rc = result.stdout.split()
    return float(seconds), float(megabytes), int(rc), result.stderr


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lines", type=int, default=100_000)
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="stvm-large-"))
    env_note = f"load {os.getloadavg()[0]:.2f}"
    big, small = work / "big.st", work / "small.st"
    n_big, n_small = generate(args.lines, big), generate(args.lines // 10, small)
    print(f"large input: {n_big:,} lines ({big.stat().st_size / 2**20:.1f} MiB), yardstick {n_small:,} lines; {env_note}")
    run = [sys.executable, "-m", "stvm", "run", "--no-cache", "--cycles", "1"]
    s_small, m_small, rc_small, _ = timed(run + [str(small)])
    s_big, m_big, rc_big, err = timed(run + [str(big)])
    print(f"first load + 1 scan: {s_big:.1f} s, peak {m_big:.0f} MB (rc {rc_big}); yardstick {s_small:.1f} s, "
          f"{m_small:.0f} MB; ratio {s_big / s_small:.1f}x for {n_big / n_small:.0f}x the lines")
    print("where it goes (one process, collector paused as in stvm):")
    subprocess.run([sys.executable, "-c", PHASES, str(big)], cwd=ROOT)
    huge = work / "huge.st"
    with huge.open("w") as fh:
        while fh.tell() < 9 * 2**20:
            fh.write(FB.format(i=fh.tell(), m=1, c=1, p=1))
    s_huge, m_huge, rc_huge, err_huge = timed([sys.executable, "-m", "stvm", "check", str(huge)])
    print(f"stvm check of a 9 MiB file: {s_huge:.2f} s, {m_huge:.0f} MB, rc {rc_huge}: {err_huge.strip().splitlines()[0]}")


if __name__ == "__main__":
    main()
