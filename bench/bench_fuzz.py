"""Larger fuzz runs of tests/cli/test_input_fuzz.py (issue 17) and tests/security/test_fuzz.py
(issue 34: TMSCT frames against the emulator, DAP messages, values and paths, XML sources): the
same properties (no traceback, the documented exit code or reply, the server still serving)
with many more examples than CI runs.

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
    # (--examples 2000 takes tens of minutes on two cores: the emulator and XML properties
    # send real frames and run `stvm check` per example)
    args = parser.parse_args()
    env = dict(os.environ, STVM_FUZZ_EXAMPLES=str(args.examples))
    started = time.monotonic()
    result = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                             "tests/cli/test_input_fuzz.py", "tests/security/test_fuzz.py"], cwd=ROOT, env=env)
    print(f"{args.examples} examples per input kind in {time.monotonic() - started:.0f} s "
          f"(load {os.getloadavg()[0]:.2f})")
    return result.returncode


if __name__ == "__main__":
    raise SystemExit(main())
