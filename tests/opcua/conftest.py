"""Fixtures of the OPC UA tests (the helpers live in `opcua_helpers`)."""

import pytest

import stvm
from opcua_helpers import THESIS, Running


@pytest.fixture(scope="session")
def thesis_project():
    return stvm.load(THESIS)


@pytest.fixture
def running(thesis_project):
    run = Running(thesis_project)
    yield run
    run.close()
