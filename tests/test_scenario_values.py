"""A scenario's values meet the checks `--set` applies (stvm/scenario.py `to_st_value`).

A TOML scalar is read as the IEC literal it spells: `5` into a TIME is refused (it would be 5 ns),
an INT out of range, a REAL beyond its type or `true` into an INT are usage errors (exit 2) found
before the first scan, naming the scenario, the event and the variable; good values are stored."""

from __future__ import annotations

import pytest

from core_helpers import cli, write_st

PROGRAM = """
PROGRAM Main
VAR t : TIME; n : INT; r : REAL; b : BOOL; END_VAR
n := n + 1;
END_PROGRAM
"""


def scenario(tmp_path, body: str):
    path = tmp_path / "s.toml"
    path.write_text(body, encoding="utf-8")
    return path


def at_scan_2(variable: str, value: str) -> str:
    return f'[[at]]\nscan = 2\nset = {{ "Main.{variable}" = {value} }}\n'


@pytest.mark.parametrize("variable, value, message", [
    ("t", "5", "Main.t: '5' is not a duration: write it as TIME"),
    ("n", "70000", "Main.n: 70000 is out of range for INT (-32768..32767)"),
    ("n", "true", "Main.n: cannot store TRUE in an INT variable"),
    ("r", "1e40", "Main.r: 1e+40 is out of range for REAL"),
    ("r", "inf", "Main.r: inf is not a number a variable can hold"),
    # 0 and 1 are BOOL literals (IEC 61131-3 table 5; issue 34 item 12), 2 is not
    ("b", "2", "Main.b: '2' is not a BOOL: write TRUE or FALSE (or 1 or 0)"),
])
@pytest.mark.parametrize("command", ["run", "trace"])
def test_a_value_the_variable_cannot_hold_is_a_usage_error_before_the_first_scan(
        command, variable, value, message, tmp_path):
    extra = ["--cycles", "3"] + (["-o", str(tmp_path / "t.jsonl")] if command == "trace" else [])
    rc, out, err = cli([command, write_st(PROGRAM), *extra, "--scenario", scenario(tmp_path, at_scan_2(variable, value))])
    assert rc == 2, err
    assert "s.toml: [[at]] #1: set: " + message in err, err
    assert "Traceback" not in err and "internal error" not in err


def test_the_initial_set_table_is_checked_the_same_way(tmp_path):
    rc, out, err = cli(["run", write_st(PROGRAM), "--cycles", "1",
                        "--scenario", scenario(tmp_path, '[set]\n"Main.t" = 5\n')])
    assert rc == 2 and "s.toml: [set]: Main.t: '5' is not a duration" in err, err


@pytest.mark.parametrize("variable, value, shown", [
    ("t", '"T#5ms"', "Main.t = T#5ms"),
    ("n", "12", "Main.n = 13"),          # stored after scan 2, incremented by scan 3
    ("r", "2.5", "Main.r = 2.5"),
    ("b", "true", "Main.b = TRUE"),
])
def test_good_values_are_stored(variable, value, shown, tmp_path):
    rc, out, err = cli(["run", write_st(PROGRAM), "--cycles", "3", "--print", f"Main.{variable}",
                        "--scenario", scenario(tmp_path, at_scan_2(variable, value))])
    assert rc == 0, err
    assert shown in out, out
