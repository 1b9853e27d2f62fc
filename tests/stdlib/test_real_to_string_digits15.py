"""`real_to_string_format=digits15`, the TwinCAT profile's REAL/LREAL_TO_STRING
(stvm/stdlib/conversions.py, docs/dialects.md): an LREAL rounded to 15 significant digits, below
0.01 a mantissa and a power of ten as TcUnit's duration messages read on a TwinCAT runtime."""

from __future__ import annotations

import pytest

from core_helpers import run_st
from stvm.settings import RealToStringFormat, SysmacSettings
from stvm.stdlib.conversions import real_to_text


@pytest.mark.parametrize("value, text", [
    (0.06999999999999999, b"0.07"),          # a sum of 10 ms steps: 15 digits round it back
    (0.09999999999999999, b"0.1"),
    (6.149999999999999, b"6.15"),
    (1234567.76, b"1234567.76"),
    (43123923124.745423, b"43123923124.7454"),
    (5.0099618, b"5.0099618"),               # as TcUnit logs a 5 s test on TwinCAT
    (-23.0, b"-23.0"),
    (0.0, b"0.0"),
    (0.01, b"0.01"),
    (0.0099385, b"9.9385e-3"),               # TcUnit on TwinCAT: duration=9.9385e-3
    (1.715e-4, b"1.715e-4"),
    (1.1e-5, b"1.1e-5"),
    (8.6e-6, b"8.6e-6"),
    (0.001, b"1.0e-3"),
    (-0.005, b"-5.0e-3"),
    (1e20, b"1E+20"),
    (float("inf"), b"#INF"),
])
def test_lreal_text(value, text):
    assert real_to_text(value, 64, RealToStringFormat.DIGITS15) == text


def test_a_real_keeps_its_shortest_text_and_the_small_form():
    assert real_to_text(44.400001525878906, 32, RealToStringFormat.DIGITS15) == b"44.4"
    assert real_to_text(0.0010000000474974513, 32, RealToStringFormat.DIGITS15) == b"1.0e-3"


def test_the_twincat_profile_prints_it_and_sysmac_keeps_c_exp():
    # ten additions of 0.01 give 0.09999999999999999 in binary floating point
    source = ("PROGRAM Main VAR s : STRING; x : LREAL; i : INT; END_VAR\n"
              "FOR i := 1 TO 10 DO x := x + 0.01; END_FOR\ns := LREAL_TO_STRING(x); END_PROGRAM")
    prints = ["Main.s"]
    assert run_st(source, prints=prints, settings=SysmacSettings(dialect="twincat"))["Main.s"] == b"0.1"
    assert run_st(source, prints=prints, settings=SysmacSettings(dialect="codesys"))["Main.s"] == b"0.09999999999999999"
    assert run_st(source, prints=prints, settings=SysmacSettings(dialect="sysmac"))["Main.s"] == b"1.00000000000000e-01"
