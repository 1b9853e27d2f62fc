"""`stvm test` (stvm/testrunner) on MiniUnit, this folder's small TcUnit-shaped framework
(fixtures/MiniUnit): the messages, the summary, -k, the timeout, faults, missing libraries and
the exit codes, without TcUnit itself (tests/testrunner/test_tcunit.py runs TcUnit)."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from tests.core_helpers import cli

FIXTURES = Path(__file__).resolve().parent / "fixtures"
MINI = FIXTURES / "MiniUnit"
PROJECT = FIXTURES / "mini_project"

SUMMARY = re.compile(r"stvm test: (\d+) suite\(s\), (\d+) test\(s\): (.*) in ([0-9.]+) s of virtual time "
                     r"\((\d+) scans, [0-9.]+ s wall\)")


def _lines(out: str) -> list[str]:
    return out.splitlines()


def _summary(out: str) -> re.Match:
    found = [m for m in map(SUMMARY.fullmatch, out.splitlines()) if m]
    assert len(found) == 1, out
    return found[0]


def test_fixture_project_messages_summary_and_exit_code():
    rc, out, err = cli(["test", PROJECT])
    assert rc == 1, err
    lines = _lines(out)
    # every ADSLOGSTR message, one line each, the message type of its mask first, in order
    assert lines[:8] == [
        "error: FAILED TEST 'MiniProject.PRG_TEST.CounterSuite@WrongOnPurpose', EXP: 5, ACT: 1, MSG: fails on purpose",
        "error: FAILED TEST 'MiniProject.PRG_TEST.CounterSuite@WrongOnPurpose', EXP: TRUE, ACT: FALSE, MSG: not full either",
        "error: | ==========TESTS FINISHED RUNNING==========",
        "error: | Test suites: 2",
        "error: | Tests: 6",
        "error: | Failed tests: 1",
        "hint: | Project: MiniProject",
        "warning: | MiniUnit is a fixture, not TcUnit",
    ]
    summary = _summary(out)
    assert summary.group(1, 2, 3) == ("2", "6", "4 passed, 1 failed, 1 skipped")
    # 6 cycles for SpansCycles, then one message every second 10 ms scan
    assert summary.group(4, 5) == ("0.170", "17")
    assert lines[-1] == "FAILED PRG_TEST.CounterSuite::WrongOnPurpose: fails on purpose"
    assert err == ""


def test_the_run_is_deterministic():
    first = cli(["test", PROJECT])
    second = cli(["test", PROJECT, "--no-cache"])
    strip = lambda out: re.sub(r"[0-9.]+ s wall", "", out)   # noqa: E731
    assert strip(first[1]) == strip(second[1])


def test_k_selects_what_is_reported_and_judged():
    rc, out, err = cli(["test", PROJECT, "-k", "limit"])
    assert rc == 0, err
    assert _summary(out).group(1, 2, 3) == ("2", "2", "2 passed, 4 deselected")
    assert "FAILED TEST" not in out          # the failing test is not selected
    assert "error: | Tests: 6" in out        # MiniUnit's (TcUnit's) own summary is printed as sent
    rc, out, err = cli(["test", PROJECT, "-k", "*::wrong*"])
    assert rc == 1
    assert _summary(out).group(2, 3) == ("1", "0 passed, 1 failed, 5 deselected")
    rc, out, err = cli(["test", PROJECT, "-k", "nothing*"])
    assert rc == 2
    assert "stvm: error: -k 'nothing*' selects none of the 6 test(s)" in err


def test_timeout_names_the_suites_still_running():
    rc, out, err = cli(["test", PROJECT, "--timeout", "50ms"])
    assert rc == 1
    assert err.strip() == ("stvm: error: timeout: after 0.05 s of virtual time (5 scans) these suites had not "
                           "finished: PRG_TEST.CounterSuite (waiting for TEST_FINISHED in SpansCycles)")
    assert "1 unfinished" in _summary(out).group(3)


def _project(tmp_path: Path, suites: str, program: str, manifest_extra: str = "") -> Path:
    folder = tmp_path / "proj"
    folder.mkdir()
    (folder / "stvm.toml").write_text(f"""
[project]
name = "P"
dialect = "twincat"

[libraries]
MiniUnit = "{MINI.as_posix()}"

[test]
library = "MiniUnit"
{manifest_extra}
""")
    (folder / "Suites.st").write_text(suites)
    (folder / "PRG_TEST.st").write_text(program)
    return folder


NEVER_FINISHES = """FUNCTION_BLOCK FB_Forever EXTENDS MiniUnit.FB_TestSuite
TEST('NeverEnds');
AssertTrue(Condition := TRUE, Message := 'fine, but no TEST_FINISHED');
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Quick EXTENDS MiniUnit.FB_TestSuite
TEST('Quick');
TEST_FINISHED();
END_FUNCTION_BLOCK
"""

PROGRAM = """PROGRAM PRG_TEST
VAR
    {names}
END_VAR
{calls}
MiniUnit.RUN();
END_PROGRAM
"""


def _program(**suites: str) -> str:
    return PROGRAM.format(names="\n    ".join(f"{n} : {t};" for n, t in suites.items()),
                          calls="\n".join(f"{n}();" for n in suites))


def test_a_suite_that_never_finishes_is_a_timeout_failure(tmp_path):
    folder = _project(tmp_path, NEVER_FINISHES, _program(Forever="FB_Forever", Quick="FB_Quick"),
                      'timeout = "2s"')
    rc, out, err = cli(["test", folder])
    assert rc == 1
    assert err.strip() == ("stvm: error: timeout: after 2 s of virtual time (200 scans) these suites had not "
                           "finished: PRG_TEST.Forever (waiting for TEST_FINISHED in NeverEnds)")
    assert "Traceback" not in err


FAULTS = """FUNCTION_BLOCK FB_Faulty EXTENDS MiniUnit.FB_TestSuite
VAR
    Zero : INT;
    Values : ARRAY[1..3] OF INT;
END_VAR
TEST('DividesByZero');
Values[1] := 10 / Zero;
TEST_FINISHED();
END_FUNCTION_BLOCK
"""


def test_a_test_that_faults_exits_3_with_its_st_line(tmp_path):
    folder = _project(tmp_path, FAULTS, _program(Faulty="FB_Faulty"))
    rc, out, err = cli(["test", folder])
    assert rc == 3
    first = err.splitlines()[0]
    assert re.fullmatch(r".*Suites\.st:7:1: fault: .*division by zero.*\(task DefaultTask, scan 0, t=T#0s\)", first), err
    assert err.splitlines()[-1] == "stvm: error: the tests stopped at a runtime fault in test PRG_TEST.Faulty::DividesByZero"
    assert "Traceback" not in err


def test_missing_library_folder_is_a_usage_error():
    rc, out, err = cli(["test", PROJECT, "--library", "MiniUnit=/nope/MiniUnit"])
    assert rc == 2
    assert err.strip() == "stvm: error: library MiniUnit: no such folder or .plcproj: /nope/MiniUnit"


def test_no_framework_library_is_a_usage_error(tmp_path):
    folder = tmp_path / "plain"
    folder.mkdir()
    (folder / "main.st").write_text("PROGRAM Main\nVAR x : INT; END_VAR\nx := 1;\nEND_PROGRAM\n")
    rc, out, err = cli(["test", folder])
    assert rc == 2
    assert err.startswith("stvm: error: no TcUnit library: give --library TcUnit=DIR")
    rc, out, err = cli(["test", PROJECT, "--framework", "TcUnit"])
    assert rc == 2
    assert "the test framework library TcUnit is not loaded" in err


def test_no_suite_is_a_usage_error(tmp_path):
    folder = _project(tmp_path, "", "PROGRAM PRG_TEST\nMiniUnit.RUN();\nEND_PROGRAM\n")
    rc, out, err = cli(["test", folder, "--timeout", "1s"])
    assert rc == 2
    assert "stvm: error: no test suite ran" in err


def test_compile_errors_exit_1_with_diagnostics(tmp_path):
    folder = _project(tmp_path, "FUNCTION_BLOCK FB_Bad EXTENDS MiniUnit.FB_TestSuite\nTEST(42, 43);\nEND_FUNCTION_BLOCK\n",
                      _program(Bad="FB_Bad"))
    rc, out, err = cli(["test", folder])
    assert rc == 1
    assert "Suites.st:2:1: error:" in err
    assert "Traceback" not in err


@pytest.mark.parametrize("argv, message", [
    (["--timeout", "soon"], "invalid duration 'soon'"),
    (["--timeout", "0s"], "--timeout must be positive"),
    (["--library", "bad"], "expected NAME=DIR"),
    (["--library-param", "x"], "expected LIB.PARAM=VALUE"),
])
def test_bad_options_are_usage_errors(argv, message):
    rc, out, err = cli(["test", PROJECT, *argv])
    assert rc == 2
    assert message in err


def test_library_parameters_reach_the_framework(tmp_path):
    # LogExtendedResults := FALSE: MiniUnit (like TcUnit) then sends only its ERROR messages
    rc, out, err = cli(["test", PROJECT, "--library-param", "MiniUnit.LogExtendedResults=FALSE"])
    assert rc == 1
    assert "hint: | Project: MiniProject" not in out
    assert "warning:" not in out
    assert "error: | Tests: 6" in out


def test_fixture_copied_elsewhere_keeps_its_project_name(tmp_path):
    copy = tmp_path / "elsewhere"
    shutil.copytree(PROJECT, copy)
    (copy / "stvm.toml").write_text((copy / "stvm.toml").read_text().replace('"../MiniUnit"', f'"{MINI.as_posix()}"'))
    rc, out, err = cli(["test", copy])
    assert rc == 1, err
    assert "hint: | Project: MiniProject" in out


def test_codesys_dialect_project_reads_results_from_the_suites():
    # a CfUnit-style project: plain .st in the codesys dialect, TcUnit's API, no ADS logger
    rc, out, err = cli(["test", FIXTURES / "codesys_project"])
    assert rc == 1, err
    assert _summary(out).group(1, 2, 3) == ("2", "6", "4 passed, 1 failed, 1 skipped")
    assert "error:" not in out            # no ADSLOGSTR under codesys: nothing logged
    assert out.splitlines()[-1] == "FAILED PRG_TEST.CounterSuite::WrongOnPurpose: fails on purpose"


def test_twincat_is_the_default_dialect_for_twincat_xml_libraries(tmp_path):
    from stvm.project import Options, resolve
    from stvm.testrunner.runner import default_dialect
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "X.TcGVL").write_text('<?xml version="1.0" encoding="utf-8"?><TcPlcObject Version="1.1.0.1">'
                                 '<GVL Name="X"><Declaration><![CDATA[VAR_GLOBAL\n a : INT;\nEND_VAR]]>'
                                 '</Declaration></GVL></TcPlcObject>')
    app = tmp_path / "app"
    app.mkdir()
    (app / "main.st").write_text("PROGRAM Main\nEND_PROGRAM\n")
    spec = resolve([app], Options(libraries=(("Lib", str(lib)),)))
    assert spec.dialect == "iec"
    assert default_dialect(spec).dialect == "twincat"
    (app / "stvm.toml").write_text('[project]\ndialect = "codesys"\n')
    spec = resolve([app], Options(libraries=(("Lib", str(lib)),)))
    assert default_dialect(spec).dialect == "codesys"     # the manifest decides


NESTED = """FUNCTION_BLOCK FB_Quick EXTENDS MiniUnit.FB_TestSuite
TEST('Quick');
AssertTrue(Condition := TRUE, Message := 'true');
TEST_FINISHED();
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Holder
VAR
    Inner : FB_Quick;
    Counts : ARRAY[1..50] OF INT;
END_VAR
Inner();
END_FUNCTION_BLOCK
"""

NESTED_PROGRAM = """PROGRAM PRG_TEST
VAR
    Many : ARRAY[1..2] OF FB_Quick;
    Holder : FB_Holder;
    Others : ARRAY[1..100] OF TON;
END_VAR
Many[1]();
Many[2]();
Holder();
MiniUnit.RUN();
END_PROGRAM
"""


def test_suites_in_arrays_and_inside_other_blocks_are_found(tmp_path):
    folder = _project(tmp_path, NESTED, NESTED_PROGRAM)
    rc, out, err = cli(["test", folder])
    assert rc == 0, out + err
    assert _summary(out).group(1, 2, 3) == ("3", "3", "3 passed")
    from stvm.project import resolve
    from stvm.testrunner.runner import run_tests
    run = run_tests(resolve([folder]))
    assert [s.path for s in run.suites] == ["PRG_TEST.Many[1]", "PRG_TEST.Many[2]", "PRG_TEST.Holder.Inner"]
    assert [t.id for t in run.tests] == ["PRG_TEST.Many[1]::Quick", "PRG_TEST.Many[2]::Quick",
                                        "PRG_TEST.Holder.Inner::Quick"]
    assert all(t.asserts == 1 and t.status == "passed" for t in run.tests)
