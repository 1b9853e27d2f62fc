"""WSTRING as UTF-16 (IEC 61131-3 ed. 3, 6.3.3): values are UTF-16 code units, "…" literals
(with `$hhhh` escapes), the string functions counting code units, STRING <-> WSTRING only through
conversion functions, readable printing, and the OPC UA mapping."""

from __future__ import annotations

import pytest
from asyncua import ua

from core_helpers import cli, run_st, write_st
from stvm.numeric import utf16_text, utf16_units
from stvm.opcua.datatypes import BadWrite, ua_type
from stvm.runtime.format import format_wstring
from stvm.semantics import types as t
from stvm.settings import SysmacSettings
from stvm.syntax.literals import LiteralError, decode_wstring

IEC = SysmacSettings().with_table({"dialect": "iec"}, "test")

FUNCTIONS = """
PROGRAM Main
VAR
    ws : WSTRING := "Grüße €😀";
    a, b, c, d, e, f, g, h, from_int : WSTRING;
    w5 : WSTRING[5];
    s, s2 : STRING;
    n, p, q : UINT;
    i : INT;
    same : BOOL;
END_VAR
n := LEN(ws);                   (* 9: the emoji is two code units *)
a := LEFT(ws, 3);
b := RIGHT(ws, 2);
c := MID(ws, 2, 4);
p := FIND(ws, "€");
d := CONCAT(ws, "!", "?");
e := INSERT(ws, "X", 2);
f := DELETE(ws, 2, 1);
g := REPLACE(ws, "ABC", 1, 1);
w5 := ws;                       (* cut at 5 code units *)
s := WSTRING_TO_STRING(ws);
q := LEN(s);
s2 := CONCAT(s, 'x');
h := STRING_TO_WSTRING(s2);
i := WSTRING_TO_INT("42");
from_int := INT_TO_WSTRING(-7);
same := a = "Grü";
END_PROGRAM
"""


def test_string_functions_count_code_units():
    names = ["ws", "n", "a", "b", "c", "p", "d", "e", "f", "g", "w5", "s", "q", "h", "i", "from_int", "same"]
    rc, out, err = cli(["run", write_st(FUNCTIONS), "--dialect", "iec", "--cycles", "1",
                        *[arg for v in names for arg in ("--print", f"Main.{v}")]])
    assert rc == 0, err
    assert out.splitlines() == [
        'Main.ws = "Grüße €😀"', "Main.n = 9", 'Main.a = "Grü"', 'Main.b = "😀"', 'Main.c = "ße"',
        "Main.p = 7", 'Main.d = "Grüße €😀!?"', 'Main.e = "GrXüße €😀"', 'Main.f = "üße €😀"',
        'Main.g = "ABCrüße €😀"', 'Main.w5 = "Grüße"',
        "Main.s = 'Gr$C3$BC$C3$9Fe $E2$82$AC$F0$9F$98$80'", "Main.q = 8",
        'Main.h = "Grüße €😀x"', "Main.i = 42", 'Main.from_int = "-7"', "Main.same = TRUE"]
    assert "truncated to the 5 code units of WSTRING[5]" in err


def test_values_are_utf16_code_units_in_the_api():
    values = run_st("""PROGRAM Main VAR ws : WSTRING := "a$00E9😀"; copy : WSTRING[10]; n : UINT; END_VAR
copy := ws; n := LEN(copy); END_PROGRAM""", prints=["Main.ws", "Main.n"], settings=IEC)
    assert values == {"Main.ws": "a\u00e9\ud83d\ude00", "Main.n": 4}


def test_a_string_literal_is_taken_where_a_wstring_is_expected():
    values = run_st("""PROGRAM Main VAR ws : WSTRING := 'init'; w2 : WSTRING; END_VAR
w2 := 'ok'; END_PROGRAM""", prints=["Main.ws", "Main.w2"], settings=IEC)
    assert values == {"Main.ws": "init", "Main.w2": "ok"}


@pytest.mark.parametrize("dialect", ["sysmac", "iec"])
def test_single_quoted_literals_among_wstring_inputs_are_wstrings(dialect):
    values = run_st("""PROGRAM Main VAR ws : WSTRING := 'Grüße'; n : UINT; w2 : WSTRING; s : STRING; END_VAR
n := FIND(ws, 'ü'); w2 := CONCAT(ws, '!'); s := CONCAT('a', 'b'); END_PROGRAM""",
                    prints=["Main.n", "Main.w2", "Main.s"],
                    settings=SysmacSettings().with_table({"dialect": dialect}, "test"))
    assert values == {"Main.n": 3, "Main.w2": "Grüße!", "Main.s": b"ab"}


def test_set_from_outside_and_sizeof():
    values = run_st("""PROGRAM Main VAR ws : WSTRING[4]; n : UINT; size : DINT; END_VAR
n := LEN(ws); size := SIZEOF(ws); END_PROGRAM""", prints=["Main.ws", "Main.n", "Main.size"],
                    sets={"Main.ws": "x😀"}, settings=IEC)
    assert values == {"Main.ws": "x\ud83d\ude00", "Main.n": 3, "Main.size": 10}


@pytest.mark.parametrize("line, message", [
    ("s := ws;", "error: type mismatch: cannot assign WSTRING to STRING; use WSTRING_TO_STRING"),
    ("ws := s;", "error: type mismatch: cannot assign STRING to WSTRING; use STRING_TO_WSTRING"),
    ("s := CONCAT(s, ws);", "error: CONCAT: mixes STRING and WSTRING inputs"),
    ("n := FIND(ws, s);", "error: FIND: mixes STRING and WSTRING inputs"),
    ("ok := s = ws;", "error: cannot compare STRING = WSTRING"),
    ("s := LEFT(ws, 1);", "error: type mismatch: cannot assign WSTRING to STRING"),
    ("s := \"abc\";", "error: type mismatch: cannot assign WSTRING[3] to STRING"),
    ("ws := STRING_TO_WSTRING(ws);", "error: type mismatch"),
])
def test_mixing_string_and_wstring_is_an_error(line, message):
    path = write_st(f"""PROGRAM Main
VAR ws : WSTRING; s : STRING; n : UINT; ok : BOOL; END_VAR
{line}
END_PROGRAM
""")
    rc, _, err = cli(["check", path, "--dialect", "iec"])
    assert rc == 1 and "Traceback" not in err
    assert f"{path.name}:3:" in err and message in err, err
    assert "cannot infer" not in err and err.count("error:") == 1, err   # one error, not a cascade


def test_declaration_errors():
    path = write_st("""PROGRAM Main
VAR s : STRING := "wide"; w : WSTRING[0]; END_VAR
END_PROGRAM
""")
    rc, _, err = cli(["check", path, "--dialect", "iec"])
    assert rc == 1
    assert ":2:19: error: a WSTRING literal cannot initialise STRING" in err
    assert "error: WSTRING size 0 is outside 1..1985" in err


def test_invalid_escape_in_a_wstring_literal_is_a_diagnostic():
    path = write_st('PROGRAM Main\nVAR w : WSTRING; END_VAR\nw := "a$12";\nEND_PROGRAM\n')
    rc, _, err = cli(["check", path, "--dialect", "iec"])
    assert rc == 1 and ":3:6: error: invalid escape '$1' in WSTRING literal" in err


def test_sysmac_keeps_double_quoted_text_a_string():
    # Sysmac has no WSTRING: "…" stays a STRING literal with the `double_quote_strings` warning
    path = write_st('PROGRAM Main\nVAR s : STRING; END_VAR\ns := "x";\nEND_PROGRAM\n')
    rc, _, err = cli(["check", path, "--dialect", "sysmac"])
    assert rc == 0 and "double-quoted string literal accepted as STRING" in err


def test_decode_wstring_literal():
    assert decode_wstring('"A$0042$"$$€"', IEC) == 'AB"$€'
    assert decode_wstring('"😀"', IEC) == "\ud83d\ude00"
    assert decode_wstring('"$D83D$DE00x$0000y"', IEC) == "\ud83d\ude00x"   # a NUL ends it
    with pytest.raises(LiteralError):
        decode_wstring('"$41"', IEC)   # two hex digits are a STRING escape


def test_utf16_helpers_and_format():
    assert utf16_units("a😀") == "a\ud83d\ude00" and utf16_units("abc") == "abc"
    assert utf16_text("a\ud83d\ude00") == "a😀"
    assert utf16_text("\ud83d") == "\ufffd"
    assert format_wstring('a"$\n\ud83d\ude00\ud83d\x01') == '"a$"$$$L😀$D83D$0001"'


def test_wstring_types():
    assert t.wstring_type(10).max_bytes == 10 and t.wstring_type(10).name == "WSTRING[10]"
    assert t.wstring_type(10) != t.string_type(11)
    assert t.byte_size(t.wstring_type(10)) == 22


def test_opcua_exposes_wstring_as_string():
    mapping = ua_type(t.wstring_type(3))
    assert mapping.variant == ua.VariantType.String and mapping.text == "WSTRING[3]"
    assert mapping.to_ua("\ud83d\ude00") == "😀"
    assert mapping.from_ua(ua.Variant("a😀", ua.VariantType.String)) == "a\ud83d\ude00"
    with pytest.raises(BadWrite):
        mapping.from_ua(ua.Variant("abcd", ua.VariantType.String))
    with pytest.raises(BadWrite):
        mapping.from_ua(ua.Variant(5, ua.VariantType.Int32))
