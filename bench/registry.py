"""The registry behind `python -m bench`: figures, their yardsticks, the machine, the history.

A figure is a function decorated with `@figure(...)` in a module `bench/fig_*.py` (found by
`python -m bench` on its own: adding a module, or a function to one, is all it takes). It is
called with `smoke` (True: a version that runs in seconds, for CI, whose numbers mean nothing)
and returns `Row`s. Every row carries its yardstick, measured in the same run, and the ratio is
the figure: the machine is shared and its speed drifts, a ratio drifts much less.

Yardsticks (both CPU time, so that other processes on the machine bend them less than wall time):

* `for_loop_us()`: the plainest Python FOR-100 loop, `for i in range(1, 101): s = s + i`, in a
  function (locals), best of 5 rounds, in microseconds of `time.process_time`.
* `import_lark_s()`: the CPU time (user + system, `getrusage` of the finished child) of a fresh
  `python3 -c "import lark"`, for start-up figures.
"""

from __future__ import annotations

import json
import os
import platform
import resource
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Row:
    """One figure: `value` in `unit`, its yardstick (`yard_name`, `yard` in `yard_unit`) and the
    ratio value/yard; `target` is the issue's bar as text ("<= 2x")."""

    figure: str
    value: float
    unit: str
    yard_name: str
    yard: float
    yard_unit: str
    target: str = ""
    ratio: float | None = None
    note: str = ""

    def __post_init__(self) -> None:
        if self.ratio is None and self.yard:
            self.ratio = self.value / self.yard


@dataclass
class Figure:
    name: str
    item: str              # where the bar comes from ("issue 33 item 2")
    run: Callable[[bool], list[Row]]
    module: str = ""
    tags: tuple[str, ...] = field(default_factory=tuple)


FIGURES: list[Figure] = []


def figure(name: str, item: str = "", tags: tuple[str, ...] = ()) -> Callable:
    """Register `fn(smoke: bool) -> list[Row]` as a benchmark."""
    def register(fn: Callable[[bool], list[Row]]) -> Callable[[bool], list[Row]]:
        FIGURES.append(Figure(name, item, fn, fn.__module__, tuple(tags)))
        return fn
    return register


# ---------------------------------------------------------------- yardsticks

def _for_100() -> int:
    s = 0
    for i in range(1, 101):
        s = s + i
    return s


def for_loop_us(rounds: int = 5, number: int = 2000) -> float:
    """CPU µs of one FOR-100 loop (best of `rounds` means of `number` loops)."""
    best = float("inf")
    clock = time.process_time
    for _ in range(rounds):
        started = clock()
        for _ in range(number):
            _for_100()
        best = min(best, (clock() - started) / number)
    return best * 1e6


def child_cpu(argv: list[str], env: dict[str, str] | None = None, cwd: Path = ROOT) -> float:
    """CPU seconds (user + system) of one finished child process (raises on a non-zero exit)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(argv, env=env, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} exited {done.returncode}: {done.stderr.strip()[-400:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def import_lark_s(env: dict[str, str] | None = None) -> float:
    return child_cpu([sys.executable, "-c", "import lark"], env)


# ---------------------------------------------------------------- the machine and the history

def machine() -> dict:
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cpu": model, "cores": os.cpu_count(), "python": platform.python_version(),
            "implementation": platform.python_implementation(), "system": platform.system(),
            "load": [round(x, 2) for x in os.getloadavg()]}


def git_commit() -> str:
    try:
        done = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                               capture_output=True, text=True).stdout.strip()
        return done.stdout.strip() + ("+dirty" if dirty else "")
    except OSError:
        return ""


def append_history(path: Path, rows: list[Row], info: dict, smoke: bool) -> None:
    """One JSON line per run (the figures of a run stay together with their machine)."""
    record = {"time": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "commit": git_commit(), "smoke": smoke,
              "machine": info, "rows": [asdict(r) for r in rows]}
    with path.open("a", encoding="utf-8") as out:
        out.write(json.dumps(record, sort_keys=True) + "\n")
