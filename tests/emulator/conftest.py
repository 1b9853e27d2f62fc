"""Fixtures for the emulator tests."""

from __future__ import annotations

from typing import Iterator

import pytest

from emulator import start_server
from emulator.settings import EmulatorSettings


@pytest.fixture
def server() -> Iterator:
    srv = start_server(port=0)
    try:
        yield srv
    finally:
        srv.stop()


@pytest.fixture
def fast_server() -> Iterator:
    """Motions 100x faster, so real-client tests stay quick."""
    srv = start_server(port=0, settings=EmulatorSettings(time_scale=0.01, reenter_delay_ms=50))
    try:
        yield srv
    finally:
        srv.stop()
