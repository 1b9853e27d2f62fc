"""One driver (stvm/project.py) for every command (issue 28 item 1).

One project with a manifest that matters for each stage: `[project] dialect = "codesys"` (names
ending in `_`, an error in the Sysmac dialect), `defines = ["SIM"]` (a variable declared and used
only under `{IF defined(SIM)}`) and `[sysmac] int_div_zero = "zero"` (a division by zero that
would otherwise stop the task). Every command — check, run, trace, lint, the language server,
the debugger's build, a DAP launch — must see the same files and settings and give the same
verdict; before the driver, `stvm lint` (and so the editor) read none of the manifest.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from core_helpers import cli
from stvm.lsp.stdio_client import StdioClient

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "debug"))

MANIFEST = """\
[project]
files = ["Types.st", "Main.st"]
dialect = "codesys"
defines = ["SIM"]

[sysmac]
int_div_zero = "zero"
"""

TYPES = "TYPE Mode_ : (Idle, Busy); END_TYPE\n"

MAIN = """\
PROGRAM Main
VAR
    count_ : INT;
    divisor : INT := 0;
    quotient : INT := 7;
    mode : Mode_ := Mode_#Idle;
END_VAR
{IF defined(SIM)}
VAR
    sim_scans : INT;
END_VAR
{END_IF}
count_ := count_ + 1;
quotient := count_ / divisor;
{IF defined(SIM)}
sim_scans := sim_scans + 1;
{END_IF}
END_PROGRAM
"""


@pytest.fixture
def project(tmp_path) -> Path:
    (tmp_path / "stvm.toml").write_text(MANIFEST)
    (tmp_path / "Types.st").write_text(TYPES)
    (tmp_path / "Main.st").write_text(MAIN)
    return tmp_path


def _expected(project: Path):
    from stvm.project import resolve
    spec = resolve([project / "Main.st"])
    return spec, [str(project / "Types.st"), str(project / "Main.st")]


def test_the_spec_holds_the_manifest_settings_for_a_file_files_or_the_folder(project):
    from stvm.project import Options, resolve
    from stvm.settings import Dialect, IntDivZero
    specs = [resolve([project / "Main.st"]), resolve([project / "Main.st", project / "Types.st"]),
             resolve([project])]
    for spec in specs:
        assert [p.name for p in spec.files] == ["Types.st", "Main.st"]
        assert spec.root == project and spec.manifest["project"]["defines"] == ["SIM"]
        assert spec.settings.dialect is Dialect.CODESYS and spec.dialect == "codesys"
        assert spec.settings.int_div_zero is IntDivZero.ZERO
        assert dict(spec.settings.defines) == dict(specs[0].settings.defines) and "SIM" in dict(spec.settings.defines)
        assert spec.libraries == ()
    # the command line goes over the manifest
    over = resolve([project], Options(dialect="sysmac", sysmac=("int_div_zero=fault",), defines=("FAST",)))
    assert over.settings.dialect is Dialect.SYSMAC and over.settings.int_div_zero is IntDivZero.FAULT
    assert {"SIM", "FAST"} <= set(dict(over.settings.defines))


def test_check_takes_any_number_of_files_of_the_manifests_folder(project):
    for argv in (["check", project / "Main.st"], ["check", project / "Main.st", project / "Types.st"],
                 ["check", project]):
        rc, out, err = cli(argv)
        assert (rc, err) == (0, ""), (argv, err)


def test_the_thesis_project_checks_from_two_of_its_files():
    root = Path(__file__).resolve().parents[2] / "st_src"
    rc, _, err = cli(["check", root / "CBT_Connect.st", root / "CBT_MoveAbsolute.st"])
    assert (rc, err) == (0, ""), err


def test_dialect_on_the_command_line_overrides_the_manifest_in_every_command(project):
    for command in ("check", "lint"):
        rc, out, err = cli([command, project / "Main.st", "--dialect", "sysmac"])
        assert rc == 1 and "may not end with '_'" in err + out, (command, err)
    rc, _, err = cli(["run", project / "Main.st", "--cycles", "1", "--dialect", "sysmac"])
    assert rc == 1 and "may not end with '_'" in err


def test_every_command_sees_the_same_files_settings_and_verdict(project, tmp_path):
    from stvm.debug.build import load_debug
    from stvm.lint import lint
    from stvm.project import Options, check, load
    spec, files = _expected(project)
    main = project / "Main.st"

    # check: clean
    analysis, diags, _ = check([main])
    assert analysis is not None and not [d for d in diags if d.is_error]
    rc, _, err = cli(["check", main])
    assert (rc, err) == (0, "")

    # run: the SIM variable exists and the division by zero gives 0 (no fault)
    project_ = load([main])
    assert project_.settings == spec.settings and project_.root == project
    rc, out, err = cli(["run", main, "--cycles", "1", "--print", "Main.sim_scans", "--print", "Main.quotient"])
    assert rc == 0, err
    assert out.splitlines() == ["Main.sim_scans = 1", "Main.quotient = 0"]

    # trace: records the SIM variable
    out_file = tmp_path / "out.jsonl"
    rc, _, err = cli(["trace", main, "--cycles", "1", "--watch", "Main.sim_scans", "-o", out_file])
    assert rc == 0, err
    assert "Main.sim_scans" in out_file.read_text()

    # lint (API and command): the same files, no compile error (the SIM variable is declared)
    report = lint([main], Options())
    assert report.files == files and not report.has_errors
    rc, out, err = cli(["lint", main, "--format", "json"])
    assert "error" not in err and not [d for d in json.loads(out).get("diagnostics", []) if d.get("severity") == "error"]
    assert "not declared" not in out + err

    # the language server: the editor's buffer, linted with the project's settings
    lsp = pytest.importorskip("stvm.lint.lsp")
    by_uri = lsp.diagnostics_for(main, MAIN, Options())
    errors = [d for diags in by_uri.values() for d in diags if d.source == lsp.SOURCE_CHECK]
    assert errors == [], [d.message for d in errors]

    # the debugger's build: the same files and settings, lowered for debugging
    build = load_debug([main])
    assert build.project.settings == spec.settings
    assert [f for f in build.project.sources if not f.startswith("<")] == files


def test_a_dap_launch_honours_the_manifest(project):
    from dap_client import DapClient
    client = DapClient(cwd=project)
    try:
        client.launch(str(project / "Main.st"), stopOnEntry=True, cycles=3)
        client.stopped("entry")
        frame = client.top_frame()      # between scans: variables by their full path
        assert client.evaluate("Main.sim_scans", frame["id"])["result"] == "0"
        client.request("continue")
        client.wait_event("terminated")
    finally:
        client.close()
    assert "not declared" not in client.stderr()


def test_a_dap_launch_takes_a_dialect(project):
    from dap_client import DapClient, DapError
    client = DapClient(cwd=project)
    try:
        client.body("initialize", adapterID="stvm", linesStartAt1=True, columnsStartAt1=True)
        with pytest.raises(DapError, match="error"):
            client.body("launch", program=str(project / "Main.st"), dialect="sysmac")
    finally:
        client.close()


@pytest.mark.parametrize("init, errors", [({}, []), ({"dialect": "sysmac"}, ["name 'count_' may not end with '_'"])])
def test_the_language_server_honours_the_manifest_and_its_initialization_options(project, init, errors):
    """`stvm lsp` as an editor starts it: the manifest's dialect and defines, and the client's
    initializationOptions over them."""
    pytest.importorskip("pygls")
    client = StdioClient()
    try:
        client.request("initialize", {"processId": None, "rootUri": None, "capabilities": {},
                                      "initializationOptions": init})
        client.notify("initialized", {})
        uri = (project / "Main.st").resolve().as_uri()
        client.notify("textDocument/didOpen", {"textDocument": {"uri": uri, "languageId": "structured-text",
                                                                "version": 1, "text": MAIN}})
        found = [d["message"] for d in client.diagnostics(uri) if d["source"] == "stvm"]
    finally:
        client.close()
    assert found == errors
