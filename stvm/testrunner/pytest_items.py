"""pytest items for TcUnit tests (the stvm pytest plugin's collector, stvm/pytest_plugin.py).

A folder whose `stvm.toml` has a `[test]` table is a test project: pytest collects its
`stvm.toml`, runs the project once when collecting it (TcUnit's tests exist only once TcUnit has
run them: a test is declared by calling `TEST('name')` in a cycle) and makes one item per TcUnit
test, named `SUITE::TEST` (`PRG_TEST.fbCounterSuite::CountsEdges`). An item passes, fails with
TcUnit's assertion messages (`FAILED TEST '…@…', EXP: …, ACT: …, MSG: …`) as its failure text, or is
skipped (a test TcUnit skipped: its name starts with `disabled_`). A project that does not build,
does not finish in time or stops at a runtime fault gives one failing item, `stvm test run`, with
the diagnostics, the suites still running or the fault's ST line.

The run happens in every process that collects the project: under `pytest -n N` each worker
collects (and so runs) it once; the items are the same in every worker (the run is on the
virtual clock, so deterministic), which is what xdist requires.

Libraries: the manifest's `[libraries]`, plus `--stvm-library NAME=DIR` on pytest's command line
or the ini option `stvm_libraries` (lines of NAME=DIR, relative to the rootdir), for a project
whose manifest names its library without a folder (`[libraries.TcUnit]` with parameters only).
"""

from __future__ import annotations

from pathlib import Path

import pytest

RUN_ITEM = "stvm test run"


class STTestFailure(Exception):
    """A failed TcUnit test (or a run that did not finish): its text is the failure report."""


def collect_file(file_path: Path, parent):
    """The collector of a `stvm.toml` with a `[test]` table, else None."""
    from stvm.manifest import ManifestError, read_manifest   # lazy: start-up (pytest loads the plugin always)
    if file_path.name != "stvm.toml":
        return None
    try:
        manifest = read_manifest(file_path)
    except ManifestError:
        return None      # not this plugin's business: stvm reports it where the project is used
    if "test" not in manifest:
        return None
    return TcUnitProject.from_parent(parent, path=file_path)


def _libraries(config) -> tuple[tuple[str, str], ...]:
    items = list(config.getoption("stvm_library", default=None) or [])
    try:
        items += [line for line in config.getini("stvm_libraries") if line.strip()]
    except ValueError:
        pass
    root = Path(config.rootpath)
    out = []
    for item in items:
        name, sep, folder = item.partition("=")
        if not sep or not name.strip().isidentifier() or not folder.strip():
            raise pytest.UsageError(f"--stvm-library {item!r}: expected NAME=DIR")
        path = Path(folder.strip())
        out.append((name.strip(), str(path if path.is_absolute() else root / path)))
    return tuple(out)


class TcUnitProject(pytest.File):
    """A TcUnit test project: its `stvm.toml`."""

    def collect(self):
        from stvm.project import LoadError, Options, resolve   # lazy: start-up
        from stvm.testrunner.runner import TestRunError, default_dialect, run_tests   # lazy: start-up
        group = pytest.mark.xdist_group(name=str(self.path.parent))
        try:
            spec = default_dialect(resolve([self.path.parent], Options(libraries=_libraries(self.config))))
            run = run_tests(spec, watchdog_s=None)
        except LoadError as exc:
            yield RunItem.from_parent(self, name=RUN_ITEM, text="the test project does not build:\n" + exc.render())
            return
        except (TestRunError, ValueError) as exc:
            hint = " (under pytest: --stvm-library NAME=DIR or the ini option stvm_libraries)" \
                if "--library" in str(exc) else ""
            yield RunItem.from_parent(self, name=RUN_ITEM, text=str(exc) + hint)
            return
        for case in run.tests:
            item = TcUnitItem.from_parent(self, name=case.id, case=case)
            item.add_marker(group)
            yield item
        problem = _run_problem(run)
        if problem:
            yield RunItem.from_parent(self, name=RUN_ITEM, text=problem)


def _run_problem(run) -> str | None:
    from stvm.testrunner.cli import timeout_message   # lazy: start-up
    if run.fault is not None:
        where = f" in test {run.fault_test}" if run.fault_test else ""
        return f"the tests stopped at a runtime fault{where}:\n" + run.fault.render(run.sources)
    if run.timed_out:
        return timeout_message(run)
    if not run.suites:
        return "no test suite ran: declare instances of FBs that EXTEND TcUnit.FB_TestSuite in a PROGRAM " \
               "that calls TcUnit.RUN()"
    return None


class TcUnitItem(pytest.Item):
    """One TcUnit test, `SUITE::TEST`."""

    def __init__(self, *, case, **kwargs) -> None:
        super().__init__(**kwargs)
        self.case = case
        # no fixtures; an empty mapping because some plugins' hooks read `item.funcargs` of
        # every item (pytest-lsp's pytest_runtest_call fails on an item without it)
        self.funcargs: dict = {}

    def runtest(self) -> None:
        case = self.case
        if case.status == "skipped":
            pytest.skip("disabled in the source (its name starts with disabled_)")
        if case.status == "failed":
            lines = case.failures or [f"assertion failed: {case.message}"]
            raise STTestFailure("\n".join(lines))
        if case.status == "unfinished":
            raise STTestFailure(f"{case.id} did not reach TEST_FINISHED() before the run ended")

    def repr_failure(self, excinfo, style=None):
        if isinstance(excinfo.value, STTestFailure):
            return str(excinfo.value)
        return super().repr_failure(excinfo, style)

    def reportinfo(self):
        return self.path, None, self.name


class RunItem(pytest.Item):
    """The run of a project that did not build, finish or run to the end."""

    def __init__(self, *, text: str, **kwargs) -> None:
        super().__init__(**kwargs)
        self.text = text
        self.funcargs: dict = {}   # see TcUnitItem

    def runtest(self) -> None:
        raise STTestFailure(self.text)

    def repr_failure(self, excinfo, style=None):
        if isinstance(excinfo.value, STTestFailure):
            return str(excinfo.value)
        return super().repr_failure(excinfo, style)

    def reportinfo(self):
        return self.path, None, self.name
