"""Libraries with namespaces (stvm/libraries.py): a folder or .plcproj loaded as library NAME,
its POUs and types reached as `NAME.X`; `--library NAME=DIR`, `[libraries]` in stvm.toml; and
the TwinCAT syntax a library like TcUnit is written in (dotted type names, constant subrange
bounds, AND_THEN / OR_ELSE, FOR over an array element, `METHOD M : T;`)."""

from __future__ import annotations

from pathlib import Path

import pytest

from stvm.project import load
from stvm.libraries import Library, LibraryError, parse_option
from stvm.settings import DEFAULT_SETTINGS
from tests.core_helpers import cli, write_files

TWINCAT = DEFAULT_SETTINGS.with_table({"dialect": "twincat"}, "test")

LIB = {
    "GVL_Param.TcGVL": """<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <GVL Name="GVL_Param" Id="{8914b509-ade2-41d9-a869-a8850ad59b87}" ParameterList="True">
    <Declaration><![CDATA[{attribute 'qualified_only'}
VAR_GLOBAL CONSTANT
    MaxItems : UINT := 4;
END_VAR
]]></Declaration>
  </GVL>
</TcPlcObject>
""",
    "E_Kind.st": """
TYPE E_Kind : (Small := 1, Large := 2); END_TYPE
""",
    "FB_Base.st": """
FUNCTION_BLOCK FB_Base
VAR
    count : UINT(0..GVL_Param.MaxItems);
    kind : E_Kind := E_Kind.Large;
END_VAR
METHOD PUBLIC Bump : UINT;
VAR_INPUT
    step : UINT;
END_VAR
IF count < GVL_Param.MaxItems AND_THEN step > 0 THEN
    count := count + 1;
END_IF
Bump := count;
END_METHOD
END_FUNCTION_BLOCK
""",
    "Twice.st": """
FUNCTION Twice : INT
VAR_INPUT x : INT; END_VAR
Twice := 2 * x;
END_FUNCTION
""",
}

USER = """
FUNCTION_BLOCK FB_Mine EXTENDS MyLib.FB_Base
END_FUNCTION_BLOCK

PROGRAM Main
VAR
    fb : FB_Mine;
    n : UINT;
    t : INT;
    k : MyLib.E_Kind;
    arr : ARRAY[1..2] OF INT;
    total : INT;
    calls : INT;
    seen : BOOL;
END_VAR
n := fb.Bump(step := 1);
t := MyLib.Twice(x := 21);
IF n > MyLib.GVL_Param.MaxItems THEN t := 0; END_IF
k := MyLib.E_Kind.Small;
FOR arr[1] := 1 TO 3 DO
    total := total + arr[1];
END_FOR
seen := FALSE OR_ELSE TRUE;
END_PROGRAM
"""


def _lib_folder() -> Path:
    return write_files(LIB)[0].parent


def test_a_library_folder_is_reached_by_its_name_and_runs() -> None:
    user = write_files({"main.st": USER})
    project = load(user, TWINCAT, use_cache=False, libraries=[Library("MyLib", _lib_folder())])
    vm = project.start()
    vm.run(cycles=5)
    assert vm["Main.n"] == 4          # the subrange bound GVL_Param.MaxItems stops the count
    assert vm["Main.t"] == 42
    assert vm["Main.total"] == 5 * 6  # FOR over an array element: 1 + 2 + 3 in each of 5 scans
    assert vm["Main.seen"] is True


def test_and_then_skips_its_right_operand() -> None:
    src = """
VAR_GLOBAL calls : INT; END_VAR
PROGRAM Main
VAR a : BOOL; b : BOOL; n : INT; END_VAR
a := FALSE AND_THEN Count();
b := TRUE OR_ELSE Count();
a := TRUE AND_THEN Count();
n := calls;
END_PROGRAM
FUNCTION Count : BOOL
calls := calls + 1;
Count := TRUE;
END_FUNCTION
"""
    vm = load(write_files({"m.st": src}), TWINCAT, use_cache=False).start()
    vm.run(cycles=1)
    assert vm["Main.n"] == 1 and vm["Main.a"] is True


def test_the_command_line_and_the_manifest_name_libraries(tmp_path) -> None:
    user = write_files({"main.st": USER})[0]
    rc, out, err = cli(["check", "--dialect", "twincat", "--library", f"MyLib={_lib_folder()}", user])
    assert rc == 0, err
    project = tmp_path / "proj"
    project.mkdir()
    (project / "main.st").write_text(user.read_text())
    (project / "stvm.toml").write_text(f'[project]\ndialect = "twincat"\n[libraries]\nMyLib = "{_lib_folder()}"\n')
    rc, out, err = cli(["check", project])
    assert rc == 0, err


def test_without_the_library_its_names_are_unknown() -> None:
    user = write_files({"main.st": USER})[0]
    rc, out, err = cli(["check", "--dialect", "twincat", user])
    assert rc == 1 and "FB_Base" in err


@pytest.mark.parametrize("text", ["MyLib", "=dir", "1x=dir", "MyLib="])
def test_a_malformed_library_option_is_a_usage_error(text) -> None:
    with pytest.raises(LibraryError):
        parse_option(text)
    rc, out, err = cli(["check", "--library", text, "x.st"])
    assert rc == 2 and "NAME=DIR" in err and "Traceback" not in err


def test_a_missing_library_folder_is_one_clear_error(tmp_path) -> None:
    user = write_files({"main.st": "PROGRAM Main\nEND_PROGRAM\n"})[0]
    rc, out, err = cli(["check", "--library", f"Gone={tmp_path / 'nowhere'}", user])
    assert rc == 1 and "library Gone" in err and "Traceback" not in err


def test_a_method_header_may_end_with_a_semicolon() -> None:
    src = """
FUNCTION_BLOCK FB
METHOD PUBLIC Get : INT; // TwinCAT writes this
VAR_INPUT x : INT; END_VAR
Get := x + 1;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR fb : FB; y : INT; END_VAR
y := fb.Get(x := 1);
END_PROGRAM
"""
    vm = load(write_files({"m.st": src}), TWINCAT, use_cache=False).start()
    vm.run(cycles=1)
    assert vm["Main.y"] == 2
