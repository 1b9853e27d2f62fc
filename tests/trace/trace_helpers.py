"""Paths shared by the trace tests (not conftest.py: several test folders have one, and test
modules import these names)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
THESIS = ROOT / "st_src"
SCENARIOS = THESIS / "scenarios"
GOLDEN = ROOT / "tests" / "golden"
ST = Path(__file__).resolve().parent / "st"
