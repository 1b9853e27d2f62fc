"""Suite-wide setup: `stvm` importable from a checkout, a private compile cache, golden updates.

* The compile cache goes to a temporary folder for the whole session (never the user's cache).
* `pytest --update-goldens` (or STVM_UPDATE_GOLDENS=1) rewrites snapshot files instead of
  comparing them (tests/semantics/diagnostics/*.stderr).
"""

from __future__ import annotations

import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TESTS = Path(__file__).resolve().parent
for p in (str(ROOT), str(TESTS)):
    if p not in sys.path:
        sys.path.insert(0, p)

if not os.environ.get("STVM_TESTS_KEEP_CACHE"):       # set it to use STVM_CACHE_DIR as given
    os.environ["STVM_CACHE_DIR"] = tempfile.mkdtemp(prefix="stvm-test-cache-")
    atexit.register(shutil.rmtree, os.environ["STVM_CACHE_DIR"], ignore_errors=True)
    # the compile cache's signing key too (stvm/cache.py), never the user's own
    os.environ["STVM_CACHE_KEY_FILE"] = os.path.join(tempfile.mkdtemp(prefix="stvm-test-key-"), "cache.key")


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--update-goldens", action="store_true", default=False,
                     help="rewrite golden/snapshot files instead of comparing them")


@pytest.fixture(scope="session")
def update_goldens(request: pytest.FixtureRequest) -> bool:
    return bool(request.config.getoption("--update-goldens") or os.environ.get("STVM_UPDATE_GOLDENS"))
