"""`ruff check` (pyflakes F and syntax errors E9, configured in pyproject.toml) finds nothing in
stvm/, emulator/, tests/ and bench/: an unused import or variable, an undefined name or an
f-string without a placeholder fails the suite."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CHECKED = ("stvm", "emulator", "tests", "bench")


@pytest.mark.skipif(importlib.util.find_spec("ruff") is None, reason="ruff is in the test extra: pip install -e .[test]")
def test_ruff_finds_nothing():
    result = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "--output-format", "concise",
                             *CHECKED], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "All checks passed" in result.stdout
