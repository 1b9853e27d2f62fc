"""Start-up time (issue 16, items 1 and 4): what a check-on-save, a pre-commit hook or a CI matrix
of small runs pays per call, measured as a user sees it: whole fresh processes.

Run: python bench/bench_startup.py [--runs 7]

Every figure is the CPU time (user + system) of a fresh `stvm` process, read from the OS
(getrusage of the finished child), the median of --runs runs, each run paired with a run of the
yardstick `python -c "import lark"` (same interpreter, same moment: A B A B ...) and printed with
the median of the pair ratios, so a machine that speeds up or slows down during the run does not
bend the ratio.

* warm: the cache holds this project (one run before the measured ones).
* cold: a fresh process with an empty stvm cache (a new STVM_CACHE_DIR each run); the stdlib's
  units ship prebuilt with stvm (stvm/stdlib/prebuilt.py), so they count as installed, not cached.
* cold, no grammar cache either: also a new TMPDIR, where Lark keeps its parser tables, as on
  a machine where stvm never ran.

Targets (issue 16): run tiny <= 2x, warm check of the thesis <= 2.5x, cold check of st_src/ <= 1.0 s.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TINY = "PROGRAM Main\nVAR x : BOOL; END_VAR\nx := NOT x;\nEND_PROGRAM\n"


def stvm_command() -> list[str]:
    script = Path(sys.executable).with_name("stvm")
    return [str(script)] if script.exists() else [sys.executable, "-m", "stvm"]


def cpu_of(argv: list[str], env: dict[str, str]) -> float:
    """CPU seconds (user + system) of one finished child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(argv, env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in (0,):
        raise SystemExit(f"{' '.join(argv)} exited {done.returncode}: {done.stderr.strip()[:400]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


class Fresh:
    """Environment of one measured run: a cache (and temp) folder per run when cold."""

    def __init__(self, base: dict[str, str], cache: str | None, tmpdir: bool) -> None:
        self.base, self.cache, self.tmpdir = base, cache, tmpdir

    def env(self) -> tuple[dict[str, str], list[str]]:
        """The environment of one run and the folders to remove after it."""
        env, made = dict(self.base), []
        env["STVM_CACHE_DIR"] = self.cache or tempfile.mkdtemp(prefix="bench-startup-cache-")
        if not self.cache:
            made.append(env["STVM_CACHE_DIR"])
        if self.tmpdir:
            env["TMPDIR"] = tempfile.mkdtemp(prefix="bench-startup-tmp-")
            made.append(env["TMPDIR"])
        return env, made


def figure(name: str, argv: list[str], fresh: Fresh, runs: int, yardstick: list[str], target: str) -> dict:
    a, b, ratios = [], [], []
    for _ in range(runs):
        env, made = fresh.env()
        a.append(cpu_of(argv, env))
        b.append(cpu_of(yardstick, fresh.base))
        ratios.append(a[-1] / b[-1])
        for folder in made:
            shutil.rmtree(folder, ignore_errors=True)
    row = {"name": name, "cpu": statistics.median(a), "yard": statistics.median(b),
           "ratio": statistics.median(ratios), "lo": min(ratios), "hi": max(ratios), "target": target}
    print(f"| {name} | {row['cpu']:.3f} s | {row['yard']:.3f} s | {row['ratio']:.2f}x "
          f"({row['lo']:.2f}-{row['hi']:.2f}) | {target} |", flush=True)
    return row


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=7)
    args = ap.parse_args()
    stvm = stvm_command()
    yardstick = [sys.executable, "-c", "import lark"]
    work = Path(tempfile.mkdtemp(prefix="bench-startup-"))
    tiny = work / "tiny.st"
    tiny.write_text(TINY)
    base = {k: v for k, v in os.environ.items() if k not in ("STVM_CACHE_DIR", "TMPDIR")}
    warm_cache = str(work / "cache")
    base_env = dict(base, STVM_CACHE_DIR=warm_cache)
    # fill the warm cache (and Lark's grammar cache in the default temp dir)
    for argv in ([*stvm, "run", str(tiny), "--cycles", "1"], [*stvm, "check", "st_src/PnP_Example.st"],
                 [*stvm, "check", "st_src/"]):
        cpu_of(argv, base_env)
    print(f"machine: {platform.node()}, {os.cpu_count()} cores, {platform.machine()}, Python "
          f"{platform.python_version()}, load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"yardstick: `python -c \"import lark\"` (same interpreter), paired run by run; "
          f"CPU seconds (user+sys), median of {args.runs}\n")
    print("| figure | stvm CPU | yardstick CPU | ratio (min-max) | target |")
    print("|---|---|---|---|---|")
    warm = Fresh(base, warm_cache, tmpdir=False)
    cold = Fresh(base, None, tmpdir=False)
    colder = Fresh(base, None, tmpdir=True)
    figure("`stvm run tiny.st --cycles 1`, warm cache", [*stvm, "run", str(tiny), "--cycles", "1"], warm,
           args.runs, yardstick, "<= 2x")
    figure("`stvm check st_src/PnP_Example.st`, warm cache", [*stvm, "check", "st_src/PnP_Example.st"], warm,
           args.runs, yardstick, "<= 2.5x")
    figure("`stvm check st_src/`, cold (empty stvm cache)", [*stvm, "check", "st_src/"], cold,
           args.runs, yardstick, "<= 1.0 s CPU")
    figure("`stvm check st_src/`, cold, no Lark grammar cache either", [*stvm, "check", "st_src/"], colder,
           args.runs, yardstick, "(<= 1.0 s CPU)")
    figure("`stvm run tiny.st --cycles 1`, cold (empty stvm cache)", [*stvm, "run", str(tiny), "--cycles", "1"],
           cold, args.runs, yardstick, "")
    print(f"\nload average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
