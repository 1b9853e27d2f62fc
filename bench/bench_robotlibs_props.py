"""The robot-library property tests (issue 31) with many more examples than CI: each library's
tests/<lib>/test_*_props.py with STVM_PROPS_EXAMPLES examples (default 100), one library after the
other; prints examples, wall time and the result per library.

    python bench/bench_robotlibs_props.py [--examples N] [rockwell schneider kuka cbt_v2]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
LIBS = {"rockwell": "tests/rockwell/test_rockwell_props.py", "schneider": "tests/schneider/test_schneider_props.py",
        "kuka": "tests/kuka/test_kuka_props.py", "cbt_v2": "tests/cbt_v2/test_v2_props.py"}


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--examples", type=int, default=100)
    parser.add_argument("libs", nargs="*", default=list(LIBS))
    args = parser.parse_args()
    env = dict(os.environ, STVM_PROPS_EXAMPLES=str(args.examples), PYTHONPATH=str(REPO))
    failed = 0
    for lib in args.libs:
        start = time.perf_counter()
        run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:xdist", "-p", "no:cacheprovider",
                              LIBS[lib]], cwd=REPO, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - start
        result = "passed" if run.returncode == 0 else "FAILED"
        failed += run.returncode != 0
        print(f"{lib:10s} examples={args.examples:5d} wall={wall:7.1f}s  {result}")
        if run.returncode:
            print(run.stdout[-3000:])
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
