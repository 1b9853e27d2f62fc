"""Subrange types (IEC 61131-3 ed. 3 6.4.4.3): check-time errors for constants out of range,
`subrange_check` for values computed at run time, and located variables (`AT %I*`)."""

from __future__ import annotations

import pytest

from core_helpers import check_text, cli, run_st, write_st
from stvm.settings import SysmacSettings

PROGRAM = """
TYPE Pct : INT(0..100); END_TYPE
TYPE Cfg : STRUCT level : Pct := 10; off : SINT(-5..5); END_STRUCT; END_TYPE
FUNCTION Half : Pct
VAR_INPUT p : Pct; END_VAR
Half := p / 2;
END_FUNCTION
PROGRAM Main
VAR p : Pct := 50; q : INT(-5..5); c : Cfg; i : INT := 20; h : Pct; wide : DINT; n : INT; END_VAR
n := n + 1;
h := Half(p);
wide := p;                       (* a subrange into a wider type: never checked *)
p := p + i;
c.off := c.off + 1;
END_PROGRAM
"""


def test_values_inside_the_range_run_and_start_at_the_lower_bound():
    values = run_st(PROGRAM, cycles=2, prints=["Main.p", "Main.q", "Main.c.level", "Main.c.off", "Main.h", "Main.wide"])
    assert values == {"Main.p": 90, "Main.q": -5, "Main.c.level": 10, "Main.c.off": -3, "Main.h": 35, "Main.wide": 70}


def test_a_value_computed_outside_the_range_faults_at_its_statement(tmp_path):
    path = write_st(PROGRAM, folder=tmp_path)
    rc, out, err = cli(["run", path, "--cycles", "5", "--print", "Main.n", "--print", "Main.p"])
    assert rc == 3
    assert f"{path}:13:1: fault: value 110 is outside the subrange 0..100" in err
    assert "Main.n = 3" in out and "Main.p = 90" in out   # the faulting store did not happen
    assert "Traceback" not in err


def test_subrange_check_store_keeps_the_value_like_codesys():
    values = run_st(PROGRAM, cycles=5, prints=["Main.p", "Main.c.off"],
                    settings=SysmacSettings(subrange_check="store"))
    assert values == {"Main.p": 150, "Main.c.off": 0}


def test_arguments_and_results_are_checked():
    source = PROGRAM.replace("h := Half(p);", "h := Half(i * 10);")
    rc, _, err = cli(["run", write_st(source), "--cycles", "1"])
    assert rc == 3 and "fault: value 200 is outside the subrange 0..100" in err


@pytest.mark.parametrize("decl, body, message", [
    ("p : INT(0..100) := 150;", "", "4:20: error: 150 is outside the subrange INT(0..100)"),
    ("p : INT(0..100);", "p := 101;", "5:6: error: 101 is outside the subrange INT(0..100)"),
    ("p : INT(0..100);", "p := -1;", "5:6: error: -1 is outside the subrange INT(0..100)"),
    ("b : USINT(0..300);", "", "error: subrange 0..300 is empty or outside USINT (0..255)"),
    ("b : INT(10..1);", "", "error: subrange 10..1 is empty or outside INT (-32768..32767)"),
    ("b : REAL(0..1);", "", "error: subrange base must be an integer type, not REAL"),
    ("", "x := F(7);", "5:8: error: 7 is outside the subrange INT(0..5)"),
])
def test_constants_out_of_range_are_check_time_errors(decl, body, message):
    rc, err = check_text(f"""FUNCTION F : INT VAR_INPUT a : INT(0..5); END_VAR F := a; END_FUNCTION
PROGRAM Main
VAR x : INT;
{decl} END_VAR
{body}
END_PROGRAM
""")
    assert rc == 1, err
    assert message in err, err
    assert "Traceback" not in err


def test_located_variables_are_accepted_and_behave_as_plain_variables():
    values = run_st("""
PROGRAM Main
VAR bIn AT %I* : BOOL; nOut AT %Q* : INT; w AT %MW10 : WORD; x AT %IX0.1 : BOOL; END_VAR
nOut := nOut + 1; w := w + 2;
END_PROGRAM
""", cycles=3, prints=["Main.nOut", "Main.w", "Main.bIn"])
    assert values == {"Main.nOut": 3, "Main.w": 6, "Main.bIn": False}
