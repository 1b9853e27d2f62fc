"""Tc2_Utilities F_ToLCase / F_ToUCase and the TwinCAT types BIT and ST_LibVersion under
`--dialect twincat` (stvm/stdlib/tc2_system.py, tc2_utilities.st, twincat_types.st)."""

from __future__ import annotations

from stvm.settings import SysmacSettings
from stvm.stdlib.tc2_system import f_to_lcase, f_to_ucase
from tests.core_helpers import run_st

TWINCAT = SysmacSettings(dialect="twincat")


def test_case_conversion_in_st():
    src = """
PROGRAM Main
VAR a, b : T_MaxString; END_VAR
a := F_ToLCase('TO LOWER CASE 1234567890');
b := F_ToUCase(in := 'to upper case 1234567890');
END_PROGRAM
"""
    assert run_st(src, prints=["Main.a", "Main.b"], settings=TWINCAT) == \
        {"Main.a": b"to lower case 1234567890", "Main.b": b"TO UPPER CASE 1234567890"}


def test_code_page_1252_letters_and_utf8_text():
    # Beckhoff's example: 'TO LOWER CASE 1234567890 ÄÖÜß' -> 'to lower case 1234567890 äöüß'
    assert f_to_lcase(None, b"\xc4\xd6\xdc\xdf \xd7") == b"\xe4\xf6\xfc\xdf \xd7"   # × stays
    assert f_to_ucase(None, b"\xe4\xf6\xfc\xdf\xff") == b"\xc4\xd6\xdc\xdf\x9f"
    assert f_to_lcase(None, "ÄÖÜ".encode()) == "äöü".encode()     # a UTF-8 source's literal
    assert f_to_ucase(None, "äöüß".encode()) == "ÄÖÜß".encode()    # ß keeps its one letter


def test_bit_and_st_libversion():
    src = """
TYPE ST_Flags : STRUCT ready : BIT; busy : BIT; END_STRUCT END_TYPE
VAR_GLOBAL CONSTANT
    stLibVersion_Mine : ST_LibVersion := (iMajor := 1, iMinor := 3, iBuild := 2, iRevision := 0,
                                          nFlags := 0, sVersion := '1.3.2.0');
END_VAR
PROGRAM Main
VAR f : ST_Flags; major : UINT; text : STRING; END_VAR
f.ready := TRUE;
f.busy := NOT f.ready;
major := stLibVersion_Mine.iMajor;
text := stLibVersion_Mine.sVersion;
END_PROGRAM
"""
    assert run_st(src, prints=["Main.f.ready", "Main.f.busy", "Main.major", "Main.text"], settings=TWINCAT) == \
        {"Main.f.ready": True, "Main.f.busy": False, "Main.major": 1, "Main.text": b"1.3.2.0"}


def test_fb_formatstring_formats_its_arguments():
    # Beckhoff Tc2_Utilities FB_FormatString: 'Measure X: %+.10d, Y: %+.10d'-style specifications
    src = """
PROGRAM Main
VAR f : FB_FormatString; a, b, c : T_MaxString; bad : BOOL; id : UDINT; x : DINT := -42; i : INT := -1; END_VAR
f(sFormat := 'Measure X: %+.5d, Y: %u %s %.3f %%', arg1 := F_DINT(x), arg2 := F_UDINT(7),
  arg3 := F_STRING('abc'), arg4 := F_LREAL(3.14159));
a := f.sOut;
f(sFormat := '%x %X %b %o %c %5s|%-4d|', arg1 := F_BYTE(255), arg2 := F_WORD(16#BEEF), arg3 := F_USINT(5),
  arg4 := F_UINT(8), arg5 := F_BYTE(65), arg6 := F_STRING('ab'), arg7 := F_INT(7));
b := f.sOut;
f(sFormat := '%u %e', arg1 := F_INT(i), arg2 := F_REAL(1.5));
c := f.sOut;
f(sFormat := '%d %q', arg1 := F_INT(1), arg2 := F_INT(2));
bad := f.bError;
id := f.nErrId;
END_PROGRAM
"""
    assert run_st(src, prints=["Main.a", "Main.b", "Main.c", "Main.bad", "Main.id"], settings=TWINCAT) == {
        "Main.a": b"Measure X: -00042, Y: 7 abc 3.142 %",
        "Main.b": b"ff BEEF 101 10 A    ab|7   |",
        "Main.c": b"65535 1.500000e+00",          # an INT's -1 as its 16-bit pattern
        "Main.bad": True, "Main.id": 1}


def test_fb_formatstring_refuses_a_missing_or_unsuitable_argument():
    src = """
PROGRAM Main
VAR f : FB_FormatString; missing, unsuitable : BOOL; END_VAR
f(sFormat := '%d and %d', arg1 := F_INT(1));
missing := f.bError;
f(sFormat := '%s', arg1 := F_INT(1));
unsuitable := f.bError AND f.sOut = '';
END_PROGRAM
"""
    assert run_st(src, prints=["Main.missing", "Main.unsuitable"], settings=TWINCAT) == \
        {"Main.missing": True, "Main.unsuitable": True}
