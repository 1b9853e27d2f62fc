"""Larger fuzz runs of tests/cli/test_input_fuzz.py (issue 17): the same properties (no traceback,
exit in {0, 1, 2, 3}, the command ends) with many more examples than CI runs.

Run: python bench/bench_fuzz.py [--examples 2000]   (prints pytest's summary line)
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=2000, help="examples per input kind (CI: 40)")
    args = parser.parse_args()
    env = dict(os.environ, STVM_FUZZ_EXAMPLES=str(args.examples))
    started = time.monotonic()
    result = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                             "tests/cli/test_input_fuzz.py"], cwd=ROOT, env=env)
    print(f"{args.examples} examples per input kind in {time.monotonic() - started:.0f} s "
          f"(load {os.getloadavg()[0]:.2f})")
    return result.returncode


if __name__ == "__main__":
    raise SystemExit(main())
