"""pytest plugin for golden-trace tests (entry point `pytest11: stvm = stvm.pytest_plugin`).

A golden test is a few lines::

    from stvm.trace import TraceSpec

    def test_pnp_cycle(golden_trace):
        golden_trace.check("pnp_cycle", TraceSpec(["st_src/PnP_Example.st"],
                                                  scenario="st_src/scenarios/golden_pnp_cycle.toml"))

`check` runs the spec in lockstep and compares the trace with `<golden dir>/pnp_cycle.jsonl`.
On a difference the test fails with the first-divergence report (scan, time, variable, expected,
actual, the ST line that last wrote it, the scans before it) and the actual trace is written next
to the golden as `pnp_cycle.jsonl.new` (ignored by git). `pytest --update-goldens` (or the
environment variable STVM_UPDATE_GOLDENS=1) rewrites the goldens instead of comparing.

The golden directory is the ini option `stvm_golden_dir` (default `tests/golden`, relative to
the rootdir); `golden_trace.directory` changes it for one test.

The plugin also collects unit tests written in ST: a folder whose `stvm.toml` has a `[test]`
table is a TcUnit test project, and each TcUnit test becomes an item `SUITE::TEST`
(stvm/testrunner/pytest_items.py, docs/unit_tests.md). `--stvm-library NAME=DIR` (or the ini
option `stvm_libraries`) gives the folder of a library such a project uses, e.g. TcUnit.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

UPDATE_OPTION = "--update-goldens"


def pytest_addoption(parser: pytest.Parser) -> None:
    _add_update_option(parser)
    parser.addini("stvm_golden_dir", "folder of golden traces (relative to the rootdir)", default="tests/golden")
    parser.addoption("--stvm-library", action="append", default=[], metavar="NAME=DIR", dest="stvm_library",
                     help="load the folder DIR as library NAME in the ST test projects pytest collects (e.g. TcUnit)")
    parser.addini("stvm_libraries", "NAME=DIR lines: libraries of the ST test projects (relative to the rootdir)",
                  type="linelist", default=[])


def pytest_collect_file(file_path: Path, parent: pytest.Collector):
    """A `stvm.toml` with a `[test]` table: its TcUnit tests (stvm/testrunner/pytest_items.py)."""
    if file_path.name != "stvm.toml":
        return None
    from stvm.testrunner.pytest_items import collect_file   # lazy: start-up (most files are not manifests)
    return collect_file(file_path, parent)


def _add_update_option(parser: pytest.Parser) -> None:
    """Register --update-goldens once, whoever asks first.

    The option predates the plugin in stvm's own tests/conftest.py (snapshot files use it too),
    and a project's conftest may declare it as well: pytest raises ValueError for a second
    declaration, and entry-point plugins are loaded before conftest files. So the plugin both
    tolerates an earlier declaration and ignores a later identical one.
    """
    try:
        parser.addoption(UPDATE_OPTION, action="store_true", default=False,
                         help="rewrite golden trace/snapshot files instead of comparing them")
    except ValueError:
        return  # declared already: same meaning
    original = parser.addoption

    def addoption(*opts, **attrs):
        if UPDATE_OPTION in opts:
            return None
        return original(*opts, **attrs)

    parser.addoption = addoption  # type: ignore[method-assign]


def updating_goldens(config: pytest.Config) -> bool:
    return bool(config.getoption(UPDATE_OPTION, default=False) or os.environ.get("STVM_UPDATE_GOLDENS"))


class GoldenTrace:
    """The `golden_trace` fixture: run a `TraceSpec` and compare with (or rewrite) a golden."""

    def __init__(self, directory: Path, update: bool) -> None:
        self.directory = Path(directory)
        self.update = update

    def path(self, name: str) -> Path:
        return self.directory / f"{name}.jsonl"

    def check(self, name: str, spec=None, *, context: int = 5, project=None, **spec_fields):
        """Run `spec` (or `TraceSpec(**spec_fields)`), compare with the golden `name`; returns the
        `TraceRun`. Fails the test with the first-divergence report on a difference."""
        # lazy: start-up (the plugin loads with every pytest run)
        from stvm.trace import TraceSpec, compare, locate_writer, read_trace, render_report, run_trace, write_trace
        from stvm.trace.writers import to_jsonl   # lazy: start-up (the plugin loads with every pytest run)
        if spec is None:
            spec = TraceSpec(**spec_fields)
        run = run_trace(spec, project)
        golden = self.path(name)
        fresh = golden.with_name(golden.name + ".new")
        if self.update:
            write_trace(run.trace, golden)
            if fresh.exists():
                fresh.unlink()
            return run
        if not golden.exists():
            fresh.parent.mkdir(parents=True, exist_ok=True)
            fresh.write_text(to_jsonl(run.trace), encoding="utf-8")
            pytest.fail(f"no golden trace {golden}; review {fresh} and run pytest {UPDATE_OPTION}", pytrace=False)
        expected = read_trace(golden)
        divergence = compare(expected, run.trace)
        if divergence is None:
            # compare() matches frames by scan; the golden must also be byte-identical (the
            # nanosecond of every robot frame), as on every machine the emulator is exact
            text = to_jsonl(run.trace)
            committed = golden.read_text(encoding="utf-8")
            if text != committed:
                fresh.write_text(text, encoding="utf-8")
                pytest.fail(f"{golden} matches scan by scan but not byte for byte: "
                            f"{_first_line_difference(committed, text)}\nactual trace: {fresh}\n"
                            f"to accept it: pytest {UPDATE_OPTION}", pytrace=False)
            if fresh.exists():
                fresh.unlink()
            return run
        divergence.writer = locate_writer(spec, run.trace, divergence, run.project)
        fresh.write_text(to_jsonl(run.trace), encoding="utf-8")
        report = render_report(divergence, expected, run.trace, context, str(golden))
        pytest.fail(report + f"actual trace: {fresh}\nto accept it: pytest {UPDATE_OPTION}", pytrace=False)


def _first_line_difference(expected: str, actual: str) -> str:
    for number, (old, new) in enumerate(zip(expected.splitlines(), actual.splitlines()), 1):
        if old != new:
            return f"line {number}:\n  golden: {old[:200]}\n  actual: {new[:200]}"
    return f"{len(expected.splitlines())} lines in the golden, {len(actual.splitlines())} now"


@pytest.fixture
def golden_trace(request: pytest.FixtureRequest) -> GoldenTrace:
    """Golden-trace comparison (see the module docstring)."""
    config = request.config
    try:
        folder = config.getini("stvm_golden_dir")
    except ValueError:   # the fixture imported by a conftest without the plugin loaded
        folder = "tests/golden"
    directory = Path(config.rootpath) / folder
    return GoldenTrace(directory, updating_goldens(config))
