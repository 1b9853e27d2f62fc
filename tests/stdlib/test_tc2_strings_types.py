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
