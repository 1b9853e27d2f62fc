"""The stvm pytest plugin collects ST unit tests (stvm/testrunner/pytest_items.py): each test of
a `[test]` project is an item SUITE::TEST, failing with the framework's assertion lines, alone
and under `pytest -n 2`. pytest runs in a child process on a copy of the MiniUnit fixture."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = Path(__file__).resolve().parent / "fixtures"


def _copy(tmp_path: Path) -> Path:
    shutil.copytree(FIXTURES / "MiniUnit", tmp_path / "MiniUnit")
    shutil.copytree(FIXTURES / "mini_project", tmp_path / "mini_project")
    return tmp_path / "mini_project"


def _pytest(cwd: Path, *argv: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-rA", *argv],
                          cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def _outcomes(stdout: str) -> dict[str, str]:
    found = {}
    for line in stdout.splitlines():
        m = re.match(r"(PASSED|FAILED|SKIPPED|ERROR) (?:\[\d+\] )?(\S+?)(?: - .*)?$", line)
        if m and "::" in m.group(2):
            found[m.group(2).split("stvm.toml::", 1)[-1]] = m.group(1)
    return found


EXPECTED = {
    "PRG_TEST.CounterSuite::CountsEdges": "PASSED",
    "PRG_TEST.CounterSuite::StopsAtLimit": "PASSED",
    "PRG_TEST.CounterSuite::WrongOnPurpose": "FAILED",
    "PRG_TEST.CounterSuite::SpansCycles": "PASSED",
    "PRG_TEST.LimitSuite::LimitOfOne": "PASSED",
}


@pytest.mark.parametrize("workers", [[], ["-n", "2"]], ids=["one process", "xdist -n 2"])
def test_each_tcunit_test_is_an_item(tmp_path, workers):
    project = _copy(tmp_path)
    result = _pytest(tmp_path, str(project.relative_to(tmp_path)), *workers)
    assert result.returncode == 1, result.stdout + result.stderr
    outcomes = _outcomes(result.stdout)
    skipped = [line for line in result.stdout.splitlines() if line.startswith("SKIPPED")]
    assert {k: v for k, v in outcomes.items() if v != "SKIPPED"} == EXPECTED, result.stdout
    assert len(skipped) == 1 and "disabled in the source" in skipped[0], result.stdout
    # the failure text: the framework's own assertion lines, no Python traceback
    assert "FAILED TEST 'MiniProject.PRG_TEST.CounterSuite@WrongOnPurpose', EXP: 5, ACT: 1, MSG: fails on purpose\n" \
           "FAILED TEST 'MiniProject.PRG_TEST.CounterSuite@WrongOnPurpose', EXP: TRUE, ACT: FALSE, MSG: not full either" in result.stdout
    assert "Traceback" not in result.stdout
    assert re.search(r"1 failed, 4 passed, 1 skipped", result.stdout), result.stdout


def test_a_run_that_does_not_finish_is_one_failing_item(tmp_path):
    project = _copy(tmp_path)
    manifest = project / "stvm.toml"
    manifest.write_text(manifest.read_text() + 'timeout = "50ms"\n')
    result = _pytest(tmp_path, "mini_project", "-k", "run")
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILED mini_project/stvm.toml::stvm test run" in result.stdout
    assert "these suites had not finished: PRG_TEST.CounterSuite (waiting for TEST_FINISHED in SpansCycles)" \
        in result.stdout


def test_a_manifest_without_test_table_is_not_collected(tmp_path):
    project = _copy(tmp_path)
    manifest = project / "stvm.toml"
    manifest.write_text(manifest.read_text().replace('[test]\nlibrary = "MiniUnit"\n', ""))
    result = _pytest(tmp_path, "mini_project")
    assert result.returncode == 5, result.stdout + result.stderr     # pytest: no tests collected


def test_the_library_folder_from_the_command_line(tmp_path):
    project = _copy(tmp_path)
    manifest = project / "stvm.toml"
    manifest.write_text(manifest.read_text().replace('MiniUnit = "../MiniUnit"', "")
                        .replace("[libraries]\n", "[libraries.MiniUnit]\nparameters = { LogExtendedResults = false }\n"))
    moved = tmp_path / "vendor" / "MiniUnit"
    shutil.move(str(tmp_path / "MiniUnit"), moved)
    result = _pytest(tmp_path, "mini_project", "--stvm-library", f"MiniUnit={moved}", "-k", "LimitOfOne")
    assert result.returncode == 0, result.stdout + result.stderr
    assert _outcomes(result.stdout) == {"PRG_TEST.LimitSuite::LimitOfOne": "PASSED"}
