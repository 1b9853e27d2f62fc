"""Library parameters (stvm/libraries.py): the constants of a library's parameter list set from
`[libraries.NAME] parameters` in stvm.toml and `--library-param LIB.PARAM=VALUE`, before the
checker runs (so a parameter that sizes an array sizes it)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.core_helpers import cli

PARAMS_GVL = """{attribute 'gvl' := 'GVL_Param'}
{attribute 'qualified_only'}
VAR_GLOBAL CONSTANT
    Enabled : BOOL := FALSE;
    Count : UINT := 3;
    FileName : STRING := 'default.xml';
END_VAR
"""

LIB_FUNCTION = """FUNCTION GetCount : UINT
GetCount := GVL_Param.Count;
END_FUNCTION
"""

MAIN = """PROGRAM Main
VAR
    n : UINT;
    arr : ARRAY[1..GVL_Param.Count] OF INT;
    on : BOOL;
    name : STRING;
END_VAR
n := MyLib.GetCount();
on := GVL_Param.Enabled;
name := GVL_Param.FileName;
END_PROGRAM
"""


def _project(tmp_path: Path, manifest: str | None = None) -> Path:
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "params.st").write_text(PARAMS_GVL)
    (lib / "get.st").write_text(LIB_FUNCTION)
    app = tmp_path / "app"
    app.mkdir()
    (app / "main.st").write_text(MAIN)
    if manifest is not None:
        (app / "stvm.toml").write_text(manifest)
    return app


def _run(app: Path, *extra) -> tuple[int, str, str]:
    return cli(["run", app, "--cycles", "1", "--no-cache", "--print", "Main.n", "--print", "Main.arr",
                "--print", "Main.on", "--print", "Main.name", *extra])


def test_defaults_without_parameters(tmp_path):
    app = _project(tmp_path)
    rc, out, err = _run(app, "--library", f"MyLib={tmp_path / 'lib'}")
    assert rc == 0, err
    assert out.splitlines() == ["Main.n = 3", "Main.arr = [0, 0, 0]", "Main.on = FALSE", "Main.name = 'default.xml'"]


def test_command_line_parameters_by_name_and_by_list(tmp_path):
    app = _project(tmp_path)
    rc, out, err = _run(app, "--library", f"MyLib={tmp_path / 'lib'}",
                        "--library-param", "MyLib.GVL_Param.Count=5", "--library-param", "MyLib.Enabled=TRUE",
                        "--library-param", "MyLib.FileName='out/r.xml'")
    assert rc == 0, err
    assert out.splitlines() == ["Main.n = 5", "Main.arr = [0, 0, 0, 0, 0]", "Main.on = TRUE",
                                "Main.name = 'out/r.xml'"]


def test_manifest_table_with_path_and_parameters(tmp_path):
    app = _project(tmp_path, """
[libraries.MyLib]
path = "../lib"
parameters = { Count = 2, Enabled = true, FileName = "'m.xml'" }
""")
    rc, out, err = _run(app)
    assert rc == 0, err
    assert out.splitlines() == ["Main.n = 2", "Main.arr = [0, 0]", "Main.on = TRUE", "Main.name = 'm.xml'"]
    # the command line wins over the manifest, and --library gives the folder of a path-less entry
    rc, out, err = _run(app, "--library-param", "MyLib.Count=4")
    assert rc == 0, err
    assert out.splitlines()[0] == "Main.n = 4"


def test_manifest_parameters_without_path_take_the_command_line_folder(tmp_path):
    app = _project(tmp_path, """
[libraries.MyLib.parameters]
Count = 1
""")
    rc, out, err = _run(app, "--library", f"MyLib={tmp_path / 'lib'}")
    assert rc == 0, err
    assert out.splitlines()[:2] == ["Main.n = 1", "Main.arr = [0]"]
    rc, out, err = _run(app)
    assert rc == 1
    assert "[libraries.MyLib] has no path: add path = \"folder\" or give --library MyLib=DIR" in err
    assert "Traceback" not in err


@pytest.mark.parametrize("option, message", [
    ("MyLib.Missing=1", "library parameter MyLib.Missing: library MyLib has no such parameter "
                        "(its parameters: GVL_Param.Enabled, GVL_Param.Count, GVL_Param.FileName)"),
    ("MyLib.Count=(", "library parameter MyLib.Count: '(' is not an ST expression"),
    ("Other.Count=1", "library parameter Other.Count: library Other has no such parameter"),
])
def test_bad_parameters_are_one_error(tmp_path, option, message):
    app = _project(tmp_path)
    rc, out, err = _run(app, "--library", f"MyLib={tmp_path / 'lib'}", "--library-param", option)
    assert rc == 1
    assert message in err
    assert "Traceback" not in err


@pytest.mark.parametrize("option", ["Count=1", "MyLib.Count", "MyLib.=1", "MyLib.a.b.c=1"])
def test_malformed_option_is_a_usage_error(tmp_path, option):
    app = _project(tmp_path)
    rc, out, err = _run(app, "--library", f"MyLib={tmp_path / 'lib'}", "--library-param", option)
    assert rc == 2
    assert "expected LIB.PARAM=VALUE" in err


def test_a_value_of_the_wrong_type_is_reported_at_the_declaration(tmp_path):
    app = _project(tmp_path)
    rc, out, err = _run(app, "--library", f"MyLib={tmp_path / 'lib'}", "--library-param", "MyLib.Count='x'")
    assert rc == 1
    assert "params.st:5:5: error: initial value does not fit type UINT" in err


def test_a_var_stat_of_a_library_function(tmp_path):
    # its hidden global is named after the function's qualified name (TcUnit's TEST_FINISHED_NAMED)
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "count.st").write_text("FUNCTION Count : UINT\nVAR_STAT\n    Calls : UINT;\nEND_VAR\n"
                                  "Calls := Calls + 1;\nCount := Calls;\nEND_FUNCTION\n")
    app = tmp_path / "app"
    app.mkdir()
    (app / "main.st").write_text("PROGRAM Main\nVAR\n    n : UINT;\nEND_VAR\nn := MyLib.Count();\nEND_PROGRAM\n")
    rc, out, err = cli(["run", app, "--cycles", "3", "--no-cache", "--library", f"MyLib={lib}", "--print", "Main.n"])
    assert rc == 0, err
    assert out.splitlines() == ["Main.n = 3"]
