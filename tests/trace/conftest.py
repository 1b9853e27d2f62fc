"""Fixtures of the trace tests.

`golden_trace` comes from stvm's pytest plugin; importing it here makes the tests work from a
checkout where the `pytest11` entry point is not installed (with it installed, this is the same
fixture). The thesis project is loaded once per session: every run gets a fresh VM and robot.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from stvm.pytest_plugin import golden_trace  # noqa: F401  (fixture)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from trace_helpers import THESIS  # noqa: E402


@pytest.fixture(scope="session")
def thesis_project():
    from stvm.project import load
    return load([THESIS / "PnP_Example.st"])
