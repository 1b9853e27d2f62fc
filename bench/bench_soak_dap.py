"""Debug adapter soak (issue 34): the hostile messages of tests/security/test_soak_dap.py
(bodies that are not JSON or not requests, JSON nested 100,000 deep, requests with fields of the
wrong type, deep and huge expressions, a --big-mb MiB expression, 100 conditional breakpoints at
once, floods of scopes/evaluate never waited for) for --seconds on one `stvm dap` stream, while a
well-behaved loop (evaluate, threads, scopes, variables on a stopped program) keeps going; then
--churn sessions each ended by a framing error. Printed: the good loop's latency p50/p99 quiet,
under attack and after; the adapter's RSS and descriptors before, at the peak and after; what
each attack did; the churned sessions' exit codes. No pass/fail: figures side by side.

    python bench/bench_soak_dap.py [--seconds 60] [--big-mb 15] [--churn 20]
"""

from __future__ import annotations

import argparse
import collections
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "security"))

from soak_harness import print_soak  # noqa: E402
from test_soak_dap import framing_churn, soak  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--big-mb", type=int, default=15, help="size of the huge expression (limit: 16 MiB a message)")
    parser.add_argument("--churn", type=int, default=20, help="sessions ended by a framing error")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        f = soak(args.seconds, Path(tmp), quiet_rounds=100, big_mb=args.big_mb)
    print(f"dap soak: {args.seconds:.0f} s of hostile messages (load {os.getloadavg()[0]:.2f})")
    print_soak(f, "rounds of 4 requests", "adapter")
    print(f"  requests sent {f['sent']}, responses {f['answered']}, internal errors {len(f['bad'])}, "
          f"exit {f['exit']}")
    started = time.monotonic()
    ends = framing_churn(args.churn)
    codes = collections.Counter(code for code, _ in ends)
    tracebacks = sum("Traceback" in err for _, err in ends)
    print(f"  churn: {args.churn} sessions ended by a framing error in {time.monotonic() - started:.0f} s, "
          f"exit codes {dict(codes)}, tracebacks {tracebacks}")
    ok = not f["bad"] and not f["errors"] and f["exit"] == 0 and set(codes) == {2} and not tracebacks
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
