"""The pytest plugin: a golden test in a few lines, --update-goldens, the report on failure.

Runs pytest in-process (pytester) on a throw-away project, with the plugin loaded by `-p` as the
`pytest11` entry point would load it."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

COUNTER = Path(__file__).parent / "st" / "counter.st"

TEST = '''
from stvm.trace import TraceSpec

def test_counter(golden_trace):
    golden_trace.check("counter", TraceSpec(["counter.st"], cycles=10, watch=["Main.*"]))
'''


class Result:
    def __init__(self, outcome) -> None:
        self.returncode = int(outcome.ret)
        self.stdout = "\n".join(outcome.outlines)
        self.stderr = "\n".join(outcome.errlines)


@pytest.fixture(scope="module")
def _warm_imports():
    """pytester restores sys.modules after each in-process run and numpy cannot be imported
    twice: everything the inner runs import is imported out here first, before the (function
    scoped) pytester takes its snapshot."""
    from stvm.trace import TraceSpec, compare, locate_writer, run_trace
    from stvm.trace.writers import to_jsonl
    spec = TraceSpec([COUNTER], cycles=2, watch=["Main.*"])
    run = run_trace(spec)
    to_jsonl(run.trace)
    compare(run.trace, run.trace)
    locate_writer(spec, run.trace, compare(run.trace, run_trace(TraceSpec([COUNTER], cycles=2, watch=["Main.flag"])).trace)
                  or _dummy())


def _dummy():
    from stvm.trace.golden import Divergence
    return Divergence(0, 0, "signals", "", "", "signals")


@pytest.fixture
def pytest_in(_warm_imports, pytester, monkeypatch):
    monkeypatch.delenv("STVM_UPDATE_GOLDENS", raising=False)

    # an installed stvm registers the plugin through its pytest11 entry point; only a bare source
    # tree needs `-p` (loading it twice is an error)
    from importlib.metadata import entry_points
    installed = any(ep.value == "stvm.pytest_plugin" for ep in entry_points(group="pytest11"))
    load = () if installed else ("-p", "stvm.pytest_plugin")

    def run(folder: Path, *args: str) -> Result:
        # hypothesis and assertion rewriting only cost start-up time here
        return Result(pytester.runpytest_inprocess(*load, "-p", "no:cacheprovider", "-p", "no:hypothesispytest",
                                                   "--assert=plain", "-q", *args))
    return run


def test_update_then_compare_then_fail(pytester, pytest_in):
    tmp_path = pytester.path
    (tmp_path / "counter.st").write_text(COUNTER.read_text())
    (tmp_path / "test_plugin_counter_inner.py").write_text(textwrap.dedent(TEST))
    (tmp_path / "pytest.ini").write_text("[pytest]\nstvm_golden_dir = golden\n")
    first = pytest_in(tmp_path)
    assert first.returncode == 1 and "no golden trace" in first.stdout
    assert (tmp_path / "golden" / "counter.jsonl.new").exists()
    assert pytest_in(tmp_path, "--update-goldens").returncode == 0
    assert (tmp_path / "golden" / "counter.jsonl").exists()
    assert not (tmp_path / "golden" / "counter.jsonl.new").exists()
    assert pytest_in(tmp_path).returncode == 0
    source = tmp_path / "counter.st"
    source.write_text(source.read_text().replace("pair.a := counter * 2;", "pair.a := counter * 3;"))
    failed = pytest_in(tmp_path)
    assert failed.returncode == 1
    assert "first divergence at scan 0" in failed.stdout
    assert "variable: Main.pair.a" in failed.stdout and "expected: 2" in failed.stdout and "actual:   3" in failed.stdout
    assert "counter.st:" in failed.stdout and "pair.a := counter * 3;" in failed.stdout
    assert (tmp_path / "golden" / "counter.jsonl.new").exists()


def test_option_declared_by_a_conftest_too(pytester, pytest_in):
    tmp_path = pytester.path
    # stvm's own tests/conftest.py declares --update-goldens as well; both must coexist
    (tmp_path / "counter.st").write_text(COUNTER.read_text())
    (tmp_path / "test_plugin_counter_inner.py").write_text(textwrap.dedent(TEST))
    (tmp_path / "conftest.py").write_text(
        "def pytest_addoption(parser):\n"
        "    parser.addoption('--update-goldens', action='store_true', default=False)\n")
    result = pytest_in(tmp_path, "--update-goldens")
    assert result.returncode == 0, result.stdout + result.stderr
    assert (tmp_path / "tests" / "golden" / "counter.jsonl").exists()
