"""TcUnit itself, unmodified, run by `stvm test` on the example project (examples/unit_tests): its
messages, its summary, the JUnit file its FB_xUnitXmlPublisher writes (validated against
Jenkins' JUnit schema), and the pytest items. TcUnit is found through STVM_TCUNIT_DIR, else as
shared/vendor/TcUnit beside the repository (or a folder above it); without it these tests are
skipped with that reason."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.core_helpers import cli

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples" / "unit_tests"
SCHEMA = Path(__file__).resolve().parent / "data" / "jenkins-junit.xsd"


def _tcunit() -> Path | None:
    given = os.environ.get("STVM_TCUNIT_DIR")
    if given:
        return Path(given)
    for folder in [ROOT.parent, *ROOT.parent.parents][:3]:
        candidate = folder / "shared" / "vendor" / "TcUnit"
        if (candidate / "TcUnit.plcproj").is_file():
            return candidate
    return None


def _has_sysfile() -> bool:
    import importlib.util
    return importlib.util.find_spec("stvm.stdlib.sys_file") is not None


TCUNIT = _tcunit()
pytestmark = [
    pytest.mark.skipif(TCUNIT is None or not (TCUNIT / "TcUnit.plcproj").is_file(),
                       reason="TcUnit's library source not found: set STVM_TCUNIT_DIR to the folder holding "
                              "TcUnit.plcproj"),
    # TcUnit's FB_FileControl calls SysFile: a build without stvm/stdlib/sys_file.py cannot load TcUnit
    pytest.mark.skipif(not _has_sysfile(), reason="this build has no SysFile library (stvm/stdlib/sys_file.py), "
                                                  "which TcUnit's FB_xUnitXmlPublisher needs"),
]

SUMMARY = re.compile(r"stvm test: (\d+) suite\(s\), (\d+) test\(s\): (.*) in ([0-9.]+) s of virtual time "
                     r"\((\d+) scans, ([0-9.]+) s wall\)")


def _run(*argv) -> tuple[int, str, str]:
    return cli(["test", *argv, "--library", f"TcUnit={TCUNIT}"])


def _summary(out: str) -> re.Match:
    found = [m for m in map(SUMMARY.fullmatch, out.splitlines()) if m]
    assert len(found) == 1, out
    return found[0]


def _without_wall_time(out: str) -> str:
    return re.sub(r", [0-9.]+ s wall\)", ")", out)


TEST_NAMES = ["ScalesAndClamps", "FollowsAStableInput", "IgnoresAShortPulse", "CountsChanges"]


def test_example_passes_with_tcunit_messages_and_summary():
    rc, out, err = _run(EXAMPLES / "st")
    assert rc == 0, out + err
    lines = out.splitlines()
    # TcUnit's final summary, sent with ADSLOG_MSGTYPE_ERROR (FB_AdsTestResultLogger)
    start = lines.index("error: | ==========TESTS FINISHED RUNNING==========")
    assert lines[start + 1:start + 5] == ["error: | Test suites: 1", "error: | Tests: 4",
                                          "error: | Successful tests: 4", "error: | Failed tests: 0"]
    assert re.fullmatch(r"error: \| Duration: [0-9.]+", lines[start + 5])
    assert lines[start + 6] == "error: | ======================================"
    # the extended results, HINT messages: the suite, then each test
    assert "hint: | Test suite ID=0 'PRG_TEST.DebounceTest'" in lines
    for name in TEST_NAMES:
        at = lines.index(f"hint: | Test name={name}")
        assert lines[at + 1] == "hint: | Test class name=PRG_TEST.DebounceTest"
        assert re.fullmatch(r"hint: \| Test status=PASS, number of asserts=\d+, duration=[0-9.E+-]+", lines[at + 2])
    assert _summary(out).group(1, 2, 3) == ("1", "4", "4 passed")
    assert err == ""


def test_the_twincat_xml_project_runs_the_same():
    rc_st, out_st, _ = _run(EXAMPLES / "st")
    rc_tc, out_tc, err = _run(EXAMPLES / "twincat")
    assert rc_tc == rc_st == 0, err
    assert _without_wall_time(out_tc) == _without_wall_time(out_st)


def test_a_failing_test_prints_tcunit_assert_messages_and_exits_1():
    rc, out, err = _run(EXAMPLES / "st", "--define", "SHOW_FAILURE")
    assert rc == 1, err
    lines = out.splitlines()
    assert "error: FAILED TEST 'PRG_TEST.DebounceTest@FailsOnPurpose', EXP: 256, ACT: 250, " \
           "MSG: deliberately wrong" in lines
    assert "error: FAILED TEST 'PRG_TEST.DebounceTest@FailsOnPurpose', EXP: on, ACT: off, " \
           "MSG: strings differ" in lines
    assert "error: | Failed tests: 1" in lines
    assert _summary(out).group(2, 3) == ("5", "4 passed, 1 failed")
    assert lines[-1] == "FAILED PRG_TEST.DebounceTest::FailsOnPurpose: deliberately wrong"


def test_k_deselects_the_failing_test():
    rc, out, err = _run(EXAMPLES / "st", "--define", "SHOW_FAILURE", "-k", "*::[CS]*")
    assert rc == 0, out + err
    assert _summary(out).group(2, 3) == ("2", "2 passed, 3 deselected")
    assert "FAILED TEST" not in out


def test_junit_file_is_tcunits_and_valid(tmp_path):
    lxml = pytest.importorskip("lxml.etree", reason="lxml comes with the [test] extra")
    target = tmp_path / "results.xml"
    rc, out, err = _run(EXAMPLES / "st", "--define", "SHOW_FAILURE", "--junit", target)
    assert rc == 1, out + err
    assert "hint: | ==========TEST RESULTS EXPORTED===========" in out.splitlines()
    document = lxml.parse(str(target))
    schema = lxml.XMLSchema(lxml.parse(str(SCHEMA)))
    assert schema.validate(document), schema.error_log
    suites = document.getroot()
    assert suites.tag == "testsuites" and suites.get("failures") == "1"
    suite, = suites.findall("testsuite")
    assert suite.get("name") == "PRG_TEST.DebounceTest" and suite.get("tests") == "5"
    cases = {case.get("name"): case for case in suite.findall("testcase")}
    assert sorted(cases) == sorted(TEST_NAMES + ["FailsOnPurpose"])
    failed = cases["FailsOnPurpose"]
    assert failed.get("status") == "FAIL" and failed.get("classname") == "PRG_TEST.DebounceTest"
    assert failed.find("failure").get("message") == "deliberately wrong"
    assert all(cases[name].get("status") == "PASS" for name in TEST_NAMES)
    # TcUnit writes the times with LREAL_TO_STRING: TwinCAT's 15 significant digits
    # (`real_to_string_format=digits15`), so a sum of 10 ms steps reads '0.07', never '0.06999999999999999'
    times = [suites.get("time"), suite.get("time")] + [case.get("time") for case in cases.values()]
    assert all(t == repr(round(float(t), 6)) for t in times), times


def test_pytest_collects_the_tcunit_tests(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-rA",
                           str(EXAMPLES / "st"), "--stvm-library", f"TcUnit={TCUNIT}"],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stdout + done.stderr
    for name in TEST_NAMES:
        assert re.search(rf"PASSED \S*stvm.toml::PRG_TEST.DebounceTest::{name}\b", done.stdout), done.stdout
    assert "4 passed" in done.stdout


CRASHING_SUITE = """FUNCTION_BLOCK FB_Crash EXTENDS TcUnit.FB_TestSuite
VAR
    zero, q : INT;
END_VAR
Crashes();

METHOD Crashes
TEST('Crashes');
q := 10 / zero;
TEST_FINISHED();
END_METHOD
END_FUNCTION_BLOCK
"""


def test_a_fault_names_the_suite_and_test_it_happened_in(tmp_path):
    import shutil
    project = tmp_path / "crash"
    shutil.copytree(EXAMPLES / "st", project)
    (project / "FB_Crash.st").write_text(CRASHING_SUITE, encoding="utf-8")
    manifest = project / "stvm.toml"
    manifest.write_text(manifest.read_text(encoding="utf-8").replace('files = [', 'files = ["FB_Crash.st", '),
                        encoding="utf-8")
    prg = project / "PRG_TEST.st"
    prg.write_text(prg.read_text(encoding="utf-8").replace("DebounceTest : FB_Debounce_Test;",
                                                           "DebounceTest : FB_Debounce_Test;\n    CrashTest : FB_Crash;"),
                   encoding="utf-8")
    rc, out, err = _run(project)
    assert rc == 3, out + err
    assert "FB_Crash.st:9:1: fault: integer division by zero" in err
    # the second suite: TcUnit's pointer to the suite being called is read after the fault
    assert err.splitlines()[-1] == "stvm: error: the tests stopped at a runtime fault in test PRG_TEST.CrashTest::Crashes"
