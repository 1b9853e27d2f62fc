"""Issue 33 item 5: start-up, as a user sees it (whole fresh processes, CPU time of the child).

* `stvm run tiny.st --cycles 1`, warm cache: <= 1.5x `python3 -c "import lark"`;
* `stvm check st_src/PnP_Example.st`, warm cache: <= 1.2x the same yardstick;
* a 100,000-line first load (`stvm run --no-cache --cycles 1` of bench/bench_large.py's
  generated program): <= 3 s CPU (printed beside the yardstick too, to compare machines).

Each stvm process is paired with a yardstick process run right after it (A B A B ...); the median
of the pair ratios is the figure. The long version takes ~1 min (the large load dominates).

Warm means warm as installed: Python's bytecode cache too. An installed stvm has its `.pyc`
files (pip writes them; an editable install writes them on first import), as Lark, the
yardstick, has its own. A session with `PYTHONDONTWRITEBYTECODE` set compiles stvm's ~40
modules from source on every run (~0.13 s CPU here, two thirds of the whole yardstick), which
measures the environment, not stvm: the figures run with bytecode written to a temporary
`PYTHONPYCACHEPREFIX` (filled by the first runs, never the source tree), for stvm and the
yardstick alike; the 100,000-line load too (a first load of the program, not of stvm's
modules). The run figure is also given without a bytecode cache, for comparison.
"""

from __future__ import annotations

import os
import statistics
import sys
import tempfile
from pathlib import Path

from bench.registry import ROOT, Row, child_cpu, figure, import_lark_s

TINY = "PROGRAM Main\nVAR x : BOOL; END_VAR\nx := NOT x;\nEND_PROGRAM\n"


def _stvm() -> list[str]:
    return [sys.executable, "-m", "stvm"]


def _bytecode_cached(env: dict[str, str], work: str) -> dict[str, str]:
    env = dict(env)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = str(Path(work) / "pycache")
    return env


def _no_bytecode_cache(env: dict[str, str]) -> dict[str, str]:
    env = dict(env, PYTHONDONTWRITEBYTECODE="1")
    env.pop("PYTHONPYCACHEPREFIX", None)
    return env


def paired(argv: list[str], env: dict[str, str], runs: int) -> tuple[float, float, float, float, float]:
    """(median CPU s, median yardstick CPU s, median ratio, min ratio, max ratio)."""
    a, b, ratios = [], [], []
    for _ in range(runs):
        a.append(child_cpu(argv, env))
        b.append(import_lark_s(env))
        ratios.append(a[-1] / b[-1])
    return statistics.median(a), statistics.median(b), statistics.median(ratios), min(ratios), max(ratios)


@figure("start-up: run tiny, check warm", item="issue 33 item 5", tags=("startup",))
def startup_figure(smoke: bool) -> list[Row]:
    runs = 1 if smoke else 9
    with tempfile.TemporaryDirectory(prefix="bench-startup-") as work:
        tiny = Path(work) / "tiny.st"
        tiny.write_text(TINY)
        env = {k: v for k, v in os.environ.items() if k != "STVM_CACHE_DIR"}
        env["STVM_CACHE_DIR"] = str(Path(work) / "cache")
        env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
        cached = _bytecode_cached(env, work)
        run = [*_stvm(), "run", str(tiny), "--cycles", "1"]
        check = [*_stvm(), "check", "st_src/PnP_Example.st"]
        for argv in (run, check):   # fill the caches (stvm's and Python's): the figures are warm
            child_cpu(argv, cached)
        import_lark_s(cached)
        rows = []
        for label, argv, target, run_env in (
                ("`stvm run tiny.st --cycles 1`, warm", run, "<= 1.5x", cached),
                ("`stvm check st_src/PnP_Example.st`, warm", check, "<= 1.2x", cached),
                ("`stvm run tiny.st --cycles 1`, warm, no .pyc (both sides)", run, "(for comparison)",
                 _no_bytecode_cache(env))):
            cpu, yard, ratio, lo, hi = paired(argv, run_env, runs)
            rows.append(Row(label, cpu, "s", "import lark", yard, "s", target, ratio=ratio,
                            note=f"median of {runs} pair ratios ({lo:.2f}-{hi:.2f})"))
    return rows


@figure("start-up: 100,000-line first load", item="issue 33 item 5", tags=("startup", "large"))
def large_figure(smoke: bool) -> list[Row]:
    sys.path.insert(0, str(ROOT / "bench"))
    from bench_large import generate
    lines = 2_000 if smoke else 100_000
    with tempfile.TemporaryDirectory(prefix="bench-large-") as work:
        source = Path(work) / "big.st"
        count = generate(lines, source)
        env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        env = _bytecode_cached(env, work)   # a first load of the program, not of stvm's own modules
        tiny = Path(work) / "tiny.st"
        tiny.write_text(TINY)
        child_cpu([*_stvm(), "run", "--no-cache", "--cycles", "1", str(tiny)], env)
        import_lark_s(env)
        cpu = child_cpu([*_stvm(), "run", "--no-cache", "--cycles", "1", str(source)], env)
        yard = import_lark_s(env)
    return [Row(f"first load of {count:,} lines + 1 scan (--no-cache), CPU", cpu, "s", "import lark", yard, "s",
                "<= 3 s CPU", note="absolute target; one fresh process")]
