"""Language server soak (issue 34): the hostile messages of tests/security/test_soak_lsp.py
(bodies that are not JSON-RPC, JSON nested 100,000 deep, unknown methods, params of the wrong
shape, cancel floods, didChange bursts, open/close churn of documents in several folders, a
--big-mb MiB document) for --seconds on one `stvm lsp` stream, while a well-behaved loop (hover,
definition, documentSymbol) keeps going. Printed: the good loop's latency p50/p99 quiet, under
attack and after; the server's RSS and descriptors before, at the peak and after; what each
attack did. No pass/fail: figures side by side.

    python bench/bench_soak_lsp.py [--seconds 60] [--big-mb 7]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "security"))

from soak_harness import print_soak  # noqa: E402
from test_soak_lsp import soak  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--big-mb", type=int, default=7, help="size of the huge document (limit: 8 MiB a source)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        f = soak(args.seconds, Path(tmp), quiet_rounds=100, big_mb=args.big_mb)
    print(f"lsp soak: {args.seconds:.0f} s of hostile messages (load {os.getloadavg()[0]:.2f})")
    print_soak(f, "rounds of 3 requests", "server")
    print(f"  requests sent {f['sent']}, answers {f['answered']}, internal errors {len(f['internal'])}, "
          f"exit {f['exit']}, traceback on stderr: {'Traceback' in f['stderr']}")
    ok = not f["internal"] and not f["errors"] and f["exit"] == 0 and "Traceback" not in f["stderr"]
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
