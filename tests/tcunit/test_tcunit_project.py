"""TcUnit, loaded unmodified as library `TcUnit` under `--dialect twincat`, with the test project
tests/fixtures/tcunit_project (one suite: a passing and a failing AssertEquals_INT).

TcUnit is not part of the repository: these tests look for its sources in $STVM_TCUNIT_DIR, else
in ../shared/vendor/TcUnit beside the repository, and skip when neither holds it."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from tests.core_helpers import cli

REPO = Path(__file__).resolve().parents[2]
PROJECT = REPO / "tests" / "fixtures" / "tcunit_project"


def tcunit_dir() -> Path | None:
    for candidate in (os.environ.get("STVM_TCUNIT_DIR"), REPO.parent / "shared" / "vendor" / "TcUnit"):
        if candidate and (Path(candidate) / "TcUnit.plcproj").is_file():
            return Path(candidate)
    return None


TCUNIT = tcunit_dir()
needs_tcunit = pytest.mark.skipif(TCUNIT is None, reason="TcUnit's sources not found: set STVM_TCUNIT_DIR "
                                                          "to the folder holding TcUnit.plcproj")

# what this work made TcUnit check without (each was an error of `stvm check` before)
FIXED = ("needs a return type", "'SysFile", "'SysDir", "SysFile\\", "FB_FormatString", "F_ToLCase",
         "unknown type 'BIT'", "ST_LibVersion", "'GVL_TcUnit' is not declared", "REF=",
         "mix of formal", "enumerator of E_XmlError", "cannot assign to function block instance",
         "an input of function block", "function block instances cannot be assigned", "__ISVALIDREF",
         "FB_init argument in a declaration", "is internal to", "constant 'CpuCounter'")


@needs_tcunit
def test_the_project_and_tcunit_check_without_the_fixed_errors():
    rc, out, err = cli(["check", "--library", f"TcUnit={TCUNIT}", str(PROJECT)])
    errors = [line for line in (out + err).splitlines() if ": error: " in line]
    assert not [e for e in errors if str(PROJECT) in e], "the test project itself must check"
    assert not [e for e in errors if any(word in e for word in FIXED)]
    assert "Traceback" not in err


@needs_tcunit
def test_tcunit_runs_the_suite_and_reports_through_adslogstr(tmp_path):
    rc, out, err = cli(["run", "--library", f"TcUnit={TCUNIT}", str(PROJECT), "--cycles", "80",   # TcUnit prints one message a cycle
                        "--files-root", str(tmp_path)])
    assert rc == 0, err
    assert "| ==========TESTS FINISHED RUNNING==========" in out
    assert re.search(r"\| Test suites: 1\b", out) and re.search(r"\| Tests: 2\b", out)
    assert re.search(r"\| Successful tests: 1\b", out) and re.search(r"\| Failed tests: 1\b", out)
    assert "two and two is not five" in out
