"""`stvm lint` on the command line: formats, exit codes, selection, suppression, config, docs."""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys
from pathlib import Path

import jsonschema
import pytest

from lint_helpers import write_st
from stvm.cli import main

ROOT = Path(__file__).resolve().parents[2]

DIVIDE = """FUNCTION_BLOCK Probe
VAR_INPUT a, b : INT; END_VAR
VAR_OUTPUT y : INT; z : UINT; END_VAR
y := a / b;
z := a;
END_FUNCTION_BLOCK
"""


def run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


def test_text_output_is_the_checkers_format_with_code_and_caret():
    path = write_st(DIVIDE)
    rc, out, err = run(["lint", str(path)])
    assert rc == 1
    assert out.splitlines()[:3] == [
        f"{path}:4:10: warning[SA204]: divisor b can be 0 here (-32768..32767): / by zero stops the task",
        "    y := a / b;",
        "             ^",
    ]
    assert f"{path}:5:6: warning[SA203]:" in out
    assert err.strip() == "2 finding(s)"


def test_clean_file_exits_0():
    path = write_st(DIVIDE.replace("y := a / b;\nz := a;", "y := a; z := 1;"))
    rc, out, err = run(["lint", str(path)])
    assert (rc, out, err.strip()) == (0, "", "0 finding(s)")


@pytest.mark.parametrize("argv, message", [
    (["lint"], "lint needs FILE"),
    (["lint", "nowhere.st"], "no such file: nowhere.st"),
    (["lint", "--select", "SA999", "X"], None),
    (["lint", "--explain", "SA000"], "unknown rule 'SA000'"),
    (["lint", "--format", "xml", "x.st"], "invalid choice"),
    (["lint", "--sysmac", "nosuch=1", "x.st"], None),
])
def test_usage_errors_exit_2(argv, message):
    if argv[-1] in ("X", "x.st"):
        argv[-1] = str(write_st(DIVIDE))
    try:
        rc, out, err = run(argv)
    except SystemExit as exc:   # argparse's own errors
        rc, err = exc.code, ""
    assert rc == 2
    if message:
        assert message in err or err == ""


def test_select_and_ignore_by_code_prefix_and_name():
    path = str(write_st(DIVIDE))
    assert "SA203" not in run(["lint", path, "--select", "SA204"])[1]
    assert "SA204" not in run(["lint", path, "--ignore", "division-by-zero"])[1]
    rc, out, _ = run(["lint", path, "--select", "SA2", "--ignore", "SA203,SA204"])
    assert (rc, out) == (0, "")


def test_noqa_comment_suppresses_that_line_only():
    text = DIVIDE.replace("y := a / b;", "y := a / b;   (* stvm: noqa SA204 *)")
    rc, out, err = run(["lint", str(write_st(text))])
    assert "SA204" not in out and "SA203" in out and "1 suppressed" in err
    text = DIVIDE.replace("z := a;", "z := a; // stvm: noqa")
    assert "SA203" not in run(["lint", str(write_st(text))])[1]
    text = DIVIDE.replace("y := a / b;", "y := a / b; (* stvm: noqa SA3 *)")
    assert "SA204" in run(["lint", str(write_st(text))])[1]


def test_stvm_toml_lint_table(tmp_path):
    (tmp_path / "probe.st").write_text(DIVIDE)
    (tmp_path / "stvm.toml").write_text('[lint]\nignore = ["SA204"]\n\n[lint.per-file-ignores]\n"probe.st" = ["SA203"]\n')
    assert run(["lint", str(tmp_path)])[0] == 0
    (tmp_path / "stvm.toml").write_text('[lint]\nselect = ["SA203"]\n')
    rc, out, _ = run(["lint", str(tmp_path / "probe.st")])
    assert rc == 1 and "SA203" in out and "SA204" not in out
    (tmp_path / "stvm.toml").write_text('[lint]\nignore = ["SA9"]\n')
    rc, _, err = run(["lint", str(tmp_path)])
    assert rc == 2 and "stvm.toml" in err
    (tmp_path / "stvm.toml").write_text('[lint]\nignorre = ["SA2"]\n')
    rc, _, err = run(["lint", str(tmp_path)])
    assert rc == 2 and "ignorre" in err


def test_compile_errors_are_printed_as_by_check_and_exit_1():
    path = write_st(DIVIDE.replace("y := a / b;", "y := c;"))
    rc, out, err = run(["lint", str(path)])
    assert rc == 1
    assert f"{path}:4:6: error: 'c' is not declared" in out
    assert "fix them to lint" in err


def test_json_format_for_editors(tmp_path):
    path = write_st(DIVIDE)
    target = tmp_path / "out.json"
    rc, out, err = run(["lint", str(path), "--format", "json", "--output", str(target)])
    assert rc == 1 and out == ""
    doc = json.loads(target.read_text())
    assert doc["version"] == 1 and doc["diagnostics"] == []
    first = doc["findings"][0]
    assert {k: first[k] for k in ("code", "name", "severity", "line", "column", "end_line", "end_column", "doc")} == \
        {"code": "SA204", "name": "division-by-zero", "severity": "warning", "line": 4, "column": 10,
         "end_line": 4, "end_column": 11, "doc": "docs/lint.md#sa204"}
    assert doc["rules"]["SA204"]["summary"]


def _sarif_schema() -> dict:
    # the OASIS SARIF 2.1.0 schema, errata01 (its "id" names the OASIS address), vendored unchanged
    # so the test pins the exact schema GitHub code scanning documents
    return json.loads((Path(__file__).parent / "data" / "sarif-schema-2.1.0.json").read_text())


def test_sarif_validates_against_the_sarif_2_1_0_schema(tmp_path):
    out = tmp_path / "lint.sarif"
    rc, _, _ = run(["lint", str(ROOT / "st_src"), "--format", "sarif", "-o", str(out)])
    assert rc == 1
    doc = json.loads(out.read_text())
    jsonschema.Draft4Validator(_sarif_schema()).validate(doc)
    run_ = doc["runs"][0]
    rules = [r["id"] for r in run_["tool"]["driver"]["rules"]]
    assert len(rules) == 20 and run_["results"]
    for result in run_["results"]:
        # what GitHub code scanning needs: a rule id it knows, a message, a file and a start line
        assert result["ruleId"] in rules and rules[result["ruleIndex"]] == result["ruleId"]
        location = result["locations"][0]["physicalLocation"]
        assert location["region"]["startLine"] >= 1 and result["message"]["text"]
        assert not location["artifactLocation"]["uri"].startswith("/")
        assert result["partialFingerprints"]["primaryLocationLineHash"]


def test_sarif_of_a_broken_file_still_validates(tmp_path):
    path = write_st("PROGRAM P\nx := ;\nEND_PROGRAM\n")
    out = tmp_path / "broken.sarif"
    rc, _, _ = run(["lint", str(path), "--format", "sarif", "-o", str(out)])
    assert rc == 1
    doc = json.loads(out.read_text())
    jsonschema.Draft4Validator(_sarif_schema()).validate(doc)
    assert doc["runs"][0]["invocations"][0]["executionSuccessful"] is False


def test_explain_prints_rationale_and_examples():
    rc, out, _ = run(["lint", "--explain", "SA201"])
    assert rc == 0
    assert out.startswith("SA201 index-out-of-bounds: ")
    assert "Example (reported):" in out and "Instead:" in out and "noqa SA201" in out
    rc, out, _ = run(["lint", "--explain", "ALL"])
    assert out.count("Family:") == 20


def test_docs_page_is_generated_and_up_to_date():
    rc = subprocess.run([sys.executable, str(ROOT / "tools" / "gen_lint_docs.py"), "--check"],
                        capture_output=True, text=True)
    assert rc.returncode == 0, rc.stderr
    page = (ROOT / "docs" / "lint.md").read_text()
    for code in ("SA101", "SA304", "SA502"):
        assert f'<a id="{code.lower()}"></a>' in page


def test_lint_runs_as_a_subprocess():
    proc = subprocess.run([sys.executable, "-m", "stvm", "lint", str(ROOT / "st_src" / "CBT_Connect.st"),
                           "--select", "SA202"], capture_output=True, text=True)
    assert proc.returncode == 1
    assert "CBT_Connect.st:490:52: warning[SA202]: ConnectionTimeOut * 100000000 is computed in DINT" in proc.stdout


def test_a_file_of_a_project_is_linted_with_its_project_but_reported_alone():
    rc, out, _ = run(["lint", str(ROOT / "st_src" / "CBT_Connect.st")])
    assert rc == 1
    files = {line.split(":")[0] for line in out.splitlines() if "warning[" in line}
    assert files == {str(ROOT / "st_src" / "CBT_Connect.st")}
