"""`python -m bench`: every figure of the performance issues in one table of ratios.

    python -m bench                  # all figures (minutes), appended to bench/history.jsonl
    python -m bench --smoke          # every figure in seconds (CI: tests/bench/test_bench_smoke.py)
    python -m bench --only trace     # the figures whose name or module contains "trace"
    python -m bench --list

Figures are the `@figure` functions of the modules `bench/fig_*.py` (bench/registry.py); each row
is printed beside its yardstick measured in the same run, and the ratio is the figure. The older
scripts (`python bench/bench_*.py`) still run on their own. The history file gets one JSON line
per run (machine, commit, rows); `--smoke` runs are not recorded unless `--history` is given.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for entry in (str(ROOT), str(ROOT / "bench")):
    if entry not in sys.path:
        sys.path.insert(0, entry)

from bench.registry import FIGURES, Row, append_history, machine  # noqa: E402

HISTORY = ROOT / "bench" / "history.jsonl"


def discover() -> None:
    for path in sorted((ROOT / "bench").glob("fig_*.py")):
        importlib.import_module(f"bench.{path.stem}")


def _number(value: float | None, unit: str = "") -> str:
    if value is None:
        return "-"
    text = f"{value:.3g}" if abs(value) < 100 else f"{value:,.0f}"
    return f"{text} {unit}".strip()


def table(rows: list[Row]) -> str:
    lines = ["| figure | value | yardstick, same run | ratio | target | note |", "|---|---|---|---|---|---|"]
    for r in rows:
        ratio = f"**{r.ratio:.2f}x**" if r.ratio is not None else "-"
        yard = f"{r.yard_name} {_number(r.yard, r.yard_unit)}" if r.yard_name else "-"
        lines.append(f"| {r.figure} | {_number(r.value, r.unit)} | {yard} | {ratio} | {r.target} | {r.note} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench", description=__doc__.split("\n\n")[0])
    parser.add_argument("--smoke", action="store_true", help="every figure in seconds (numbers mean nothing)")
    parser.add_argument("--only", action="append", default=[], metavar="TEXT",
                        help="figures whose name or module contains TEXT (repeatable)")
    parser.add_argument("--list", action="store_true", help="list the figures and exit")
    parser.add_argument("--history", type=Path, default=None,
                        help=f"append the results here (default {HISTORY.relative_to(ROOT)}; smoke runs: nowhere)")
    parser.add_argument("--no-history", action="store_true", help="do not append the results anywhere")
    args = parser.parse_args(argv)
    discover()
    chosen = [f for f in FIGURES if not args.only or any(o.lower() in (f.name + " " + f.module).lower()
                                                           for o in args.only)]
    if args.list:
        for f in chosen:
            print(f"{f.name:40s} {f.module:22s} {f.item}")
        return 0
    info = machine()
    print(f"machine: {info['cpu']}, {info['cores']} cores, {info['implementation']} {info['python']}, "
          f"{info['system']}, load average {' '.join(map(str, info['load']))}" + ("  [SMOKE: numbers mean nothing]" if args.smoke else ""),
          flush=True)
    rows: list[Row] = []
    failed = []
    for f in chosen:
        started = time.process_time()
        try:
            got = f.run(args.smoke)
        except Exception:   # noqa: BLE001 - one broken figure must not hide the others
            traceback.print_exc()
            failed.append(f.name)
            rows.append(Row(f.name, float("nan"), "", "", 0, "", note="ERROR (traceback above)"))
            continue
        rows.extend(got)
        print(f"  {f.name}: {len(got)} row(s), {time.process_time() - started:.1f} s CPU", file=sys.stderr, flush=True)
    load_after = " ".join(f"{x:.2f}" for x in __import__("os").getloadavg())
    print()
    print(table(rows))
    print(f"\nload average after: {load_after}")
    history = None if args.no_history else (args.history or (None if args.smoke else HISTORY))
    if history is not None and rows:
        append_history(history, rows, info, args.smoke)
        print(f"appended to {history}")
    if failed:
        print(f"FAILED: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
