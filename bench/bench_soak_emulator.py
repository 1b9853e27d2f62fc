"""Emulator Listen Node soak (issue 34): the attacks of tests/security/test_soak_emulator.py
(malformed frames, valid frames never read, half-open frames, connect/close churn, connections
past --max-connections) for --seconds, while one well-behaved client keeps asking the Listen
Node status. Printed: the good client's latency p50/p99 quiet, under attack and after; the
server's RSS and descriptors before, at the peak and after; what each attack did. No pass/fail:
figures side by side (the test asserts bounds on a short run).

    python bench/bench_soak_emulator.py [--seconds 60] [--max-connections 64]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "security"))

from soak_harness import print_soak  # noqa: E402
from test_soak_emulator import soak  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--max-connections", type=int, default=64)
    args = parser.parse_args()
    f = soak(args.seconds, max_connections=args.max_connections, quiet_requests=2000)
    print(f"emulator soak: {args.seconds:.0f} s of attack, max-connections {args.max_connections} "
          f"(load {os.getloadavg()[0]:.2f})")
    print_soak(f, "requests", "server")
    print(f"  refused past the limit {f['resets']}")
    print(f"  server alive: {f['alive']}; unexpected attack errors: {f['errors'] or 'none'}")
    return 0 if f["alive"] and not f["errors"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
