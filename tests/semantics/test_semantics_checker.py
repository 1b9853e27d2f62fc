"""stvm.semantics: what the checker accepts and rejects (sysmac.md 2 typing rules, name rules)."""

from __future__ import annotations

import re

import pytest

from core_helpers import check_text, cli, write_st

ERROR_AT = re.compile(r"^\S+:(\d+):\d+: error: ", re.M)

DECLS = """
TYPE Color : (Red, Green); Pt : STRUCT x : INT; END_STRUCT; END_TYPE
PROGRAM Main
VAR
  b : BOOL; si : SINT; i : INT; d : DINT; li : LINT; us : USINT; ui : UINT; ud : UDINT; ul : ULINT;
  byt : BYTE; w : WORD; dw : DWORD; lw : LWORD; r : REAL; lr : LREAL; t : TIME; dt : DT; tod : TOD; dat : DATE;
  s : STRING; s5 : STRING[5]; c : Color; p : Pt; p2 : Pt; a3 : ARRAY[1..3] OF INT; b3 : ARRAY[0..2] OF INT;
  tn : TON;
END_VAR
"""


def error_lines(source: str) -> tuple[int, set[int], str]:
    rc, err = check_text(source, "checker.st")
    assert "Traceback" not in err
    return rc, {int(x) for x in ERROR_AT.findall(err)}, err


# Each line is valid ST under sysmac.md 2 (widening chart, same-size signed<->unsigned, literals).
ACCEPTED = """
i := si; d := i; li := d; ui := us; ud := ui; ul := ud; i := us; d := ui; li := ud;
ui := i; i := ui; ud := d; d := ud; us := si; si := us; ul := li; li := ul;
r := i; r := ui; r := us; lr := d; lr := li; lr := r; r := 1.5; lr := 1.5;
w := byt; dw := w; lw := dw; w := 16#FFFF; byt := 255; w := ui; ui := w;
i := i + 1; us := us + 1; si := si - 1; ul := ul * 2; byt := byt XOR 16#FF; w := w AND 16#0F;
d := i * i; li := UDINT#16#FFFF_FFFF + DINT#1; r := r * 2.0; lr := r / 3.0; r := i * 1.5;
b := i < d; b := r >= 1.0; b := s = 'x'; b := s5 <> s; b := c = Color#Red; b := c <> Green; b := t > T#1s;
t := t + T#1s; t := t * 2; t := t / 2; dt := dt + T#1h; t := dt - dt; tod := tod + T#1m;
s := 'abc'; s5 := s; s := s5; s := CONCAT(s, 'x', s5);
c := Green; c := Color#Red; p := p2; p.x := i; a3 := b3;
tn(IN := b, PT := T#1s); b := tn.Q; t := tn.ET;
b := TRUE AND NOT b OR b XOR FALSE & b;
i := -i; d := ABS(d); lr := 2.0 ** 3; i := i MOD 3; d := d / 7;
"""


def test_valid_typing_is_accepted():
    rc, lines, err = error_lines(DECLS + ACCEPTED + "END_PROGRAM\n")
    assert rc == 0, err


REJECTED = [
    "si := i;", "i := d;", "d := li;", "us := ui;", "ui := ud;", "ud := ul;",      # narrowing
    "ui := si;", "ud := i;", "ul := d;",                                        # signed -> wider unsigned
    "r := lr;", "i := r;", "d := lr;", "r := d * 1.5;",                         # real -> narrower/int
    "r := w;", "w := r;",                                                       # bit strings and reals
    "i := s;", "s := i;", "i := 'abc';", "b := i;", "i := b;", "b := 2;",      # string/bool (0 and 1 are BOOL literals)
    "c := 1;", "i := c;", "t := 5;", "d := t;", "dt := t;", "tod := dt;",       # enums and times
    "p := 5;", "p := a3;", "a3 := p;",                                          # structs and arrays
    "i := TRUE + 1;", "s := s + s;", "b := i = 'x';", "b := c = 1;", "r := r MOD 2.0;", "t := t * t;",
    "b := NOT r;", "IF i THEN END_IF;", "WHILE r DO END_WHILE;", "REPEAT UNTIL s END_REPEAT;",
    "i := ui * 100000000;",   # UINT * DINT literal is DINT (sysmac.md 8 #7): not into INT
]


def test_each_invalid_line_is_an_error():
    body = "\n".join(REJECTED)
    first = DECLS.count("\n") + 1
    rc, lines, err = error_lines(DECLS + body + "\nEND_PROGRAM\n")
    assert rc == 1
    expected = set(range(first, first + len(REJECTED)))
    missing = sorted(REJECTED[n - first] for n in expected - lines)
    assert not missing, f"accepted but should be errors: {missing}"
    assert lines <= expected


def test_one_pass_reports_errors_from_every_pou_and_file(tmp_path):
    a = tmp_path / "a.st"
    b = tmp_path / "b.st"
    a.write_text("FUNCTION_BLOCK FA\nVAR x : INT; END_VAR\nx := nope_a;\nEND_FUNCTION_BLOCK\n"
                 "FUNCTION FF : INT\nFF := 'text';\nEND_FUNCTION\n")
    b.write_text("PROGRAM Main\nVAR i : INT; END_VAR\nIF i THEN i := nope_b; END_IF;\nEND_PROGRAM\n")
    rc, out, err = cli(["check", a, b])
    assert rc == 1
    assert len(ERROR_AT.findall(err)) == 4 and err.rstrip().endswith("4 error(s)")


@pytest.mark.parametrize(("name", "source"), [
    ("fb_contains_itself", "FUNCTION_BLOCK A VAR a : A; END_VAR END_FUNCTION_BLOCK\n"
                           "PROGRAM Main VAR x : A; END_VAR END_PROGRAM\n"),
    ("struct_contains_itself", "TYPE S : STRUCT s : S; END_STRUCT; END_TYPE\n"
                               "PROGRAM Main VAR x : S; END_VAR END_PROGRAM\n"),
    ("struct_array_of_itself", "TYPE S : STRUCT s : ARRAY[1..2] OF S; END_STRUCT; END_TYPE\n"
                               "PROGRAM Main VAR x : S; END_VAR END_PROGRAM\n"),
    ("mutual_fbs", "FUNCTION_BLOCK A VAR b : B; END_VAR END_FUNCTION_BLOCK\n"
                   "FUNCTION_BLOCK B VAR a : A; END_VAR END_FUNCTION_BLOCK\n"
                   "PROGRAM Main VAR x : A; END_VAR END_PROGRAM\n"),
])
def test_recursive_containment_is_a_diagnostic(name, source):
    path = write_st(source, f"{name}.st")
    rc, _, err = cli(["check", path])
    assert rc == 1 and ": error:" in err
    rc, _, err = cli(["run", path, "--cycles", "1", "--no-cache"])
    assert rc == 1 and "Traceback" not in err


def test_type_alias_cycle_is_a_diagnostic():
    rc, lines, err = error_lines("TYPE A : B; B : A; END_TYPE\nPROGRAM Main VAR x : A; END_VAR END_PROGRAM\n")
    assert rc == 1 and 1 in lines


@pytest.mark.parametrize("name", ["__import__", "_G", "a__b", "bad_", "P_x", "_x"])
def test_sysmac_user_name_rules(name):
    rc, err = check_text(f"PROGRAM Main\nVAR {name} : INT; END_VAR\n{name} := 1;\nEND_PROGRAM\n", "names.st", "sysmac")
    assert rc == 1 and ": error:" in err


@pytest.mark.parametrize("source", [
    "TYPE __dict__ : INT; END_TYPE\nPROGRAM Main END_PROGRAM",
    "FUNCTION_BLOCK __init__ END_FUNCTION_BLOCK\nPROGRAM Main END_PROGRAM",
    "FUNCTION __import__ : INT __import__ := 1; END_FUNCTION\nPROGRAM Main END_PROGRAM",
    "FUNCTION_BLOCK F VAR_INPUT __x : INT; END_VAR END_FUNCTION_BLOCK\nPROGRAM Main END_PROGRAM",
    "VAR_GLOBAL __g : INT; END_VAR\nPROGRAM Main END_PROGRAM",
    "PROGRAM Main VAR_TEMP __t : INT; END_VAR END_PROGRAM",
    "PROGRAM __Main END_PROGRAM",
    "PROGRAM Main VAR " + "x" * 200 + " : INT; END_VAR END_PROGRAM",
    pytest.param("TYPE S : STRUCT __class__ : INT; END_STRUCT; END_TYPE\nPROGRAM Main END_PROGRAM", id="struct_field"),
    pytest.param("TYPE E : (__x, y); END_TYPE\nPROGRAM Main END_PROGRAM", id="enumerator"),
    pytest.param("NAMESPACE __ns TYPE T : INT; END_TYPE END_NAMESPACE\nPROGRAM Main END_PROGRAM", id="namespace"),
    pytest.param("CONFIGURATION C RESOURCE R ON PLC TASK __T (INTERVAL := T#1ms, PRIORITY := 1); "
                 "PROGRAM __i WITH __T : Main; END_RESOURCE END_CONFIGURATION\nPROGRAM Main END_PROGRAM", id="task_and_instance"),
])
def test_name_rules_apply_to_every_kind_of_name(source):
    rc, err = check_text(source, "names_everywhere.st", "sysmac")
    assert rc == 1 and ": error:" in err and "Traceback" not in err


def test_system_names_from_the_stdlib_are_usable():
    rc, err = check_text("PROGRAM Main\nVAR s : _sSOCKET; o : _eBYTE_ORDER := _eBYTE_ORDER#_LOW_HIGH; "
                         "c : _eCONNECTION_STATE; END_VAR\nc := _CLOSE_WAIT;\nEND_PROGRAM\n", "sys.st")
    assert rc == 0, err


def test_enumerator_resolution_in_own_type_context():
    """A bare enumerator that exists in two enums is fine where the expected type decides."""
    rc, lines, err = error_lines("TYPE A : (One, Two); B : (Two, Three); END_TYPE\n"
                                 "PROGRAM Main\nVAR a : A; b : B; x : INT; END_VAR\n"
                                 "a := One;\nb := Three;\nCASE b OF Three: x := 1; END_CASE;\nEND_PROGRAM\n")
    assert rc == 0, err
