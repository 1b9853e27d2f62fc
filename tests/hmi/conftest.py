"""Fixtures of the HMI tests (helpers in hmi_helpers.py)."""

from __future__ import annotations

import pytest

import stvm
from hmi_helpers import THESIS, start_live_hmi


@pytest.fixture(scope="session")
def thesis_project():
    return stvm.load([str(THESIS)])


@pytest.fixture
def live_hmi(thesis_project):
    live = start_live_hmi(thesis_project)
    yield live
    live.stop()
