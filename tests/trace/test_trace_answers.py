"""`stvm trace` answers a new user can trust (issue 34 item 12): the writer of a value that comes
from a FUNCTION, METHOD or interface call, and a short run against a longer golden."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stvm.cli import main

CALLS = """INTERFACE ICalc
METHOD Calc : INT
VAR_INPUT a : INT; END_VAR
END_METHOD
END_INTERFACE

FUNCTION_BLOCK Doubler IMPLEMENTS ICalc
VAR last : INT; END_VAR
METHOD Calc : INT
VAR_INPUT a : INT; END_VAR
last := a;
Calc := a * 2;
END_METHOD
END_FUNCTION_BLOCK

FUNCTION Twice : INT
VAR_INPUT a : INT; END_VAR
Twice := a * 2;
END_FUNCTION

PROGRAM Main
VAR f : INT; x : INT; y : INT; n : INT; d : Doubler; itf : ICalc; END_VAR
itf := d;
n := n + 1;
f := Twice(n);
x := itf.Calc(n);
y := d.Calc(n);
END_PROGRAM
"""
WATCH = ["--watch", "Main.f", "--watch", "Main.x", "--watch", "Main.y", "--watch", "Main.d.last"]


@pytest.fixture
def recorded(tmp_path) -> tuple[Path, Path]:
    src = tmp_path / "calls.st"
    src.write_text(CALLS, encoding="utf-8")
    out = tmp_path / "run.jsonl"
    assert main(["trace", str(src), "--cycles", "5", *WATCH, "-o", str(out)]) == 0
    return src, out


def _golden(out: Path, dest: Path, change) -> Path:
    lines = [json.loads(line) for line in out.read_text(encoding="utf-8").splitlines()]
    dest.write_text("".join(json.dumps(change(obj)) + "\n" for obj in lines), encoding="utf-8")
    return dest


@pytest.mark.parametrize("variable, statement", [
    ("Main.f", "f := Twice(n);"),             # a FUNCTION's result
    ("Main.x", "x := itf.Calc(n);"),          # an interface call
    ("Main.y", "y := d.Calc(n);"),            # a METHOD call
    ("Main.d.last", "last := a;"),            # written inside the METHOD
])
def test_the_writer_of_a_value_from_a_call_is_the_statement(recorded, tmp_path, capsys, variable, statement) -> None:
    src, out = recorded

    def change(obj):
        if obj.get("scan") == 2:
            obj["values"][variable] = "99"
        return obj

    golden = _golden(out, tmp_path / "golden.jsonl", change)
    capsys.readouterr()
    assert main(["trace", str(src), "--cycles", "5", *WATCH, "--compare", str(golden)]) == 4
    err = capsys.readouterr().err
    assert f"variable: {variable}" in err
    assert statement in err and "scenario" not in err, err


def test_a_short_run_against_a_longer_golden_says_the_run_ended(recorded, tmp_path, capsys) -> None:
    src, out = recorded
    assert main(["trace", str(src), "--cycles", "9", *WATCH, "-o", str(tmp_path / "long.jsonl")]) == 0
    capsys.readouterr()
    assert main(["trace", str(src), "--cycles", "5", *WATCH, "--compare", str(tmp_path / "long.jsonl")]) == 4
    err = capsys.readouterr().err
    assert "this run ended after 5 scan(s)" in err and "has 9" in err and "--cycles 9" in err
    assert "first divergence at scan" not in err


HINTS = """TYPE Conn : STRUCT Connected : BOOL; Port : INT; END_STRUCT; END_TYPE
VAR_GLOBAL Cobot : Conn; END_VAR
PROGRAM Main
VAR Step : INT; END_VAR
Step := Step + 1;
END_PROGRAM
"""


@pytest.mark.parametrize("watch, hint", [
    ("Cobot.Conected", "did you mean Cobot.Connected?"),
    ("Main.Stepp", "did you mean Main.Step?"),
    ("Cobt.Connected", "did you mean Cobot?"),
    ("Cobot.Conected*", "did you mean Cobot.Connected?"),
])
def test_did_you_mean_names_the_member(tmp_path, capsys, watch: str, hint: str) -> None:
    src = tmp_path / "hints.st"
    src.write_text(HINTS, encoding="utf-8")
    assert main(["trace", str(src), "--cycles", "1", "--watch", watch, "-o", str(tmp_path / "t.jsonl")]) == 2
    assert hint in capsys.readouterr().err


def test_emulator_log_with_a_real_robot_is_refused(capsys) -> None:
    root = Path(__file__).resolve().parents[2]
    log = root / "no_such_dir_for_the_log_test" / "e.log"
    code = main(["run", str(root / "st_src" / "PnP_Example.st"), "--robot", "127.0.0.1:9",
                 "--emulator-log", str(log), "--cycles", "1"])
    assert code == 2
    assert "with --robot HOST:PORT no emulator runs" in capsys.readouterr().err
    assert not log.exists()


def test_a_tcp_path_picture_without_a_robot_is_refused(recorded, tmp_path, capsys) -> None:
    """The robot's home pose alone was drawn as the start of an empty path."""
    pytest.importorskip("matplotlib")
    src, _ = recorded
    out = tmp_path / "path.png"
    capsys.readouterr()
    assert main(["trace", str(src), "--cycles", "5", *WATCH, "-o", str(out)]) == 2
    assert "never connected to the robot" in capsys.readouterr().err
    assert not out.exists()
