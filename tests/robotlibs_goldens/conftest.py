"""Fixtures of the robot-library golden tests: stvm's `golden_trace` (imported so the tests run from
a checkout without the pytest11 entry point) and each library's project, loaded once."""

from __future__ import annotations


from stvm.pytest_plugin import golden_trace  # noqa: F401  (fixture)
