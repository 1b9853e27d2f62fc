"""Conditional compilation (CODESYS/TwinCAT `{IF defined(X)}` … `{ELSIF}` … `{ELSE}` … `{END_IF}`,
`{define}`, `{undefine}`): the branches not taken are blanked out before parsing, so the kept code
keeps its lines; defines from the source, `stvm.toml` `[project] defines` and `--define`
(stvm/syntax/conditional.py)."""

from __future__ import annotations

import pytest

from stvm.settings import DEFAULT_SETTINGS, SettingError
from stvm.syntax.conditional import preprocess
from stvm.syntax.parser import parse_text, parse_text_lark
from tests.core_helpers import assert_no_traceback, cli, run_st, write_files, write_st

BRANCHES = """{define FAST}
PROGRAM Main
VAR x : INT; y : INT; z : INT; END_VAR
{IF defined(FAST)}
x := 1;
{ELSIF defined(SLOW)}
x := 2;
{ELSE}
x := 3;
{END_IF}
{IF NOT defined(SLOW) AND (defined(FAST) OR defined(Other))}
y := 10;
{ELSE}
y := not_declared_here;
{END_IF}
(* {IF defined(Nothing)} in a comment is no directive *)
z := 7; // {END_IF} neither
END_PROGRAM
"""


def test_the_branch_taken_is_kept_and_the_others_are_blanked():
    out = run_st(BRANCHES, prints=["Main.x", "Main.y", "Main.z"])
    assert out == {"Main.x": 1, "Main.y": 10, "Main.z": 7}


def test_blanking_keeps_every_line_and_column():
    text, diags = preprocess(BRANCHES, "f.st", ())
    assert diags == []
    assert len(text) == len(BRANCHES)
    assert text.splitlines() == [line if keep else " " * len(line) for line, keep in zip(
        BRANCHES.splitlines(), [False, True, True, False, True, False, False, False, False, False,
                                False, True, False, False, False, True, True, True])]


def test_a_define_from_the_settings_chooses_another_branch():
    src = BRANCHES.replace("{define FAST}", "")
    runnable = src.replace("not_declared_here", "20")
    out = run_st(runnable, prints=["Main.x", "Main.y"], settings=DEFAULT_SETTINGS.with_defines(["SLOW"]))
    assert out == {"Main.x": 2, "Main.y": 20}
    # neither: the ELSE branch (and y's ELSE branch, which names an undeclared variable, is an error)
    rc, _, err = cli(["check", write_st(src)])
    assert rc == 1 and "14:6: error: 'not_declared_here' is not declared" in err


def test_the_kept_code_keeps_its_line_numbers_in_diagnostics():
    src = "PROGRAM Main\nVAR x : INT; END_VAR\n{IF defined(A)}\nx := 1;\n{ELSE}\nx := nope;\n{END_IF}\nEND_PROGRAM\n"
    rc, _, err = cli(["check", write_st(src)])
    assert rc == 1 and ":6:6: error: 'nope' is not declared" in err


def test_nested_ifs_undefine_and_hasvalue():
    src = """{define MODE 'fast'}
{define GONE}
{undefine GONE}
PROGRAM Main
VAR a : INT; b : INT; c : INT; END_VAR
{IF defined(OUTER)}
  {IF defined(MODE)} a := 1; {ELSE} a := 2; {END_IF}
{ELSE}
  {IF hasvalue(MODE, 'fast') AND NOT defined(GONE)} a := 3; {ELSE} a := 4; {END_IF}
{END_IF}
{IF hasvalue(MODE, 'slow')} b := 1; {ELSIF hasvalue(MODE, 'fast')} b := 2; {END_IF}
{IF defined(NEVER)} {define LATE} {END_IF}
{IF defined(LATE)} c := 1; {ELSE} c := 2; {END_IF}
END_PROGRAM
"""
    assert run_st(src, prints=["Main.a", "Main.b", "Main.c"]) == {"Main.a": 3, "Main.b": 2, "Main.c": 2}
    with_outer = run_st(src, prints=["Main.a"], settings=DEFAULT_SETTINGS.with_defines(["OUTER"]))
    assert with_outer == {"Main.a": 1}


def test_define_names_are_case_sensitive_directive_words_are_not():
    src = "PROGRAM Main\nVAR a : INT; END_VAR\n{if DEFINED(debug)} a := 1; {else} a := 2; {end_if}\nEND_PROGRAM\n"
    assert run_st(src, prints=["Main.a"], settings=DEFAULT_SETTINGS.with_defines(["DEBUG"])) == {"Main.a": 2}
    assert run_st(src, prints=["Main.a"], settings=DEFAULT_SETTINGS.with_defines(["debug"])) == {"Main.a": 1}


def test_directives_in_strings_are_text():
    src = "PROGRAM Main\nVAR s : STRING; END_VAR\ns := '{IF defined(X)}';\nEND_PROGRAM\n"
    assert run_st(src, prints=["Main.s"]) == {"Main.s": b"{IF defined(X)}"}


def test_both_parsers_see_the_same_text():
    for parse in (parse_text, parse_text_lark):
        unit, diags = parse(BRANCHES, "f.st")
        assert diags == [] and [p.name for p in unit.pous] == ["Main"]


def test_other_pragmas_still_attach():
    src = "{IF defined(X)}\n{attribute 'hide'}\n{END_IF}\n{attribute 'qualified_only'}\nVAR_GLOBAL g : INT; END_VAR\n"
    unit, diags = parse_text(src, "f.st")
    assert diags == [] and unit.globals[0].pragmas == ("attribute 'qualified_only'",)


@pytest.mark.parametrize("src, where, message", [
    ("{IF defined(A)}\nPROGRAM Main\nEND_PROGRAM\n", "1:1", "{IF} without its {END_IF}"),
    ("PROGRAM Main\n{END_IF}\nEND_PROGRAM\n", "2:1", "{END_IF} without an open {IF}"),
    ("PROGRAM Main\n  {ELSE}\nEND_PROGRAM\n", "2:3", "{ELSE} without an open {IF}"),
    ("{IF defined(A)}{ELSE}{ELSIF defined(B)}{END_IF}\n", "1:22", "{ELSIF} after the {ELSE} of this {IF}"),
    ("{IF defined(A}\n{END_IF}\n", "1:1", "the condition ends too early (expected ')')"),
    ("{IF}\n{END_IF}\n", "1:1", "an empty condition"),
    ("{IF A}\n{END_IF}\n", "1:1", "unknown operand 'A'"),
    ("{IF defined(A) = 1}\n{END_IF}\n", "1:1", "unexpected '= 1' in the condition"),
    ("{IF defined(variable: x)}\n{END_IF}\n", "1:1", "`defined(variable: …)` asks about the program"),
    ("{IF hasattribute(pou: P, 'x')}\n{END_IF}\n", "1:1", "hasattribute asks about the program"),
    ("{define}\n", "1:1", "{define} needs a name"),
])
def test_malformed_directives_are_errors_at_their_place(src, where, message):
    rc, _, err = cli(["check", write_st(src)])
    assert_no_traceback(err)
    assert rc == 1 and f":{where}: error: " in err and message in err, err


def test_stvm_toml_defines_and_the_define_option():
    src = "PROGRAM Main\nVAR a : INT; END_VAR\n{IF defined(SIM) AND hasvalue(AXES, '2')} a := 1;\n" \
          "{ELSIF defined(SIM)} a := 2; {ELSIF defined(REAL_IO)} a := 3; {ELSE} a := 4; {END_IF}\nEND_PROGRAM\n"
    main, _ = write_files({"Main.st": src, "stvm.toml": '[project]\ndefines = ["SIM", "AXES=2"]\n'})
    rc, out, err = cli(["run", main.parent, "--cycles", "1", "--print", "Main.a"])
    assert (rc, out) == (0, "Main.a = 1\n"), err
    rc, out, err = cli(["run", main.parent, "--cycles", "1", "--print", "Main.a", "--define", "AXES=3"])
    assert (rc, out) == (0, "Main.a = 2\n"), err
    alone = write_st(src)
    rc, out, err = cli(["run", alone, "--cycles", "1", "--print", "Main.a", "--define", "REAL_IO"])
    assert (rc, out) == (0, "Main.a = 3\n"), err
    rc, _, err = cli(["check", alone, "--define", "REAL_IO", "--define", "AXES='2'"])
    assert rc == 0, err


@pytest.mark.parametrize("argv_define", ["1X", "A B", "=1", ""])
def test_a_malformed_define_option_is_a_usage_error(argv_define):
    rc, _, err = cli(["check", write_st("PROGRAM Main\nEND_PROGRAM\n"), "--define", argv_define])
    assert_no_traceback(err)
    assert rc == 2 and "stvm: error: --define: a define is NAME or NAME=VALUE" in err


def test_a_malformed_manifest_define_names_the_manifest():
    main, _ = write_files({"Main.st": "PROGRAM Main\nEND_PROGRAM\n", "stvm.toml": '[project]\ndefines = ["no good"]\n'})
    rc, _, err = cli(["check", main.parent])
    assert rc == 2 and "stvm.toml: [project] defines: a define is NAME" in err
    main, _ = write_files({"Main.st": "PROGRAM Main\nEND_PROGRAM\n", "stvm.toml": '[project]\ndefines = "SIM"\n'})
    rc, _, err = cli(["check", main.parent])
    assert rc == 2 and "[project] defines must be a list of defines" in err


def test_settings_defines_are_checked_and_ordered():
    s = DEFAULT_SETTINGS.with_defines(["B", "A=1", "B=2"])
    assert s.defines == (("A", "1"), ("B", "2"))
    with pytest.raises(SettingError):
        DEFAULT_SETTINGS.with_defines(["not ok"])
    with pytest.raises(SettingError):
        type(DEFAULT_SETTINGS)(defines=(("x y", ""),))
