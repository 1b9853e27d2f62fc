"""TIME and LTIME unsigned under TwinCAT and CODESYS (the `unsigned_time` row of stvm/dialects.py):
TIME a 32-bit count of milliseconds, LTIME a 64-bit count of nanoseconds, both from 0, wrapping
like UDINT / ULINT; Sysmac and IEC keep signed 64-bit nanoseconds."""

from __future__ import annotations

import pytest

from stvm.settings import SysmacSettings
from tests.core_helpers import check_text, run_st

LTIME_MAX = "LTIME#213503D23H34M33S709MS551US615NS"   # 2^64 - 1 ns, TcUnit-Verifier's value


def _run(dialect: str, variables: str, body: str, prints: list[str], fmt: bool = False):
    src = f"PROGRAM Main\nVAR\n{variables}\nEND_VAR\n{body}\nEND_PROGRAM\n"
    return run_st(src, prints=[f"Main.{p}" for p in prints], fmt=fmt, settings=SysmacSettings(dialect=dialect))


@pytest.mark.parametrize("dialect", ["twincat", "codesys"])
def test_the_largest_ltime_literal_is_two_to_the_64_minus_one_ns(dialect):
    out = _run(dialect, f"a : LTIME := {LTIME_MAX}; b : LTIME := LTIME#1000D15H23M12S34MS2US44NS;\n"
               "u : ULINT; s : STRING; greater : BOOL; same : BOOL;",
               "u := LTIME_TO_ULINT(a); s := LTIME_TO_STRING(a); greater := a > b; same := a = a;",
               ["u", "s", "greater", "same"])
    assert out == {"Main.u": 2**64 - 1, "Main.s": b"LTIME#213503d23h34m33s709ms551us615ns",
                   "Main.greater": True, "Main.same": True}


@pytest.mark.parametrize("dialect", ["twincat", "codesys"])
def test_time_and_ltime_arithmetic_wraps_as_udint_and_ulint(dialect):
    out = _run(dialect, f"a : LTIME := {LTIME_MAX}; up : LTIME; down : LTIME; t : TIME; under : TIME;"
               " over : TIME; s : STRING; back : LTIME;",
               "up := a + LTIME#1ns; down := LTIME#0ns - LTIME#1ns; t := T#49D17H2M47S295MS;"
               " over := t + T#1ms; under := T#0ms - T#1ms; s := TO_STRING(LTIME#1ms);"
               " back := ULINT_TO_LTIME(LTIME_TO_ULINT(down));",
               ["up", "down", "over", "under", "s", "back"])
    assert out == {"Main.up": 0, "Main.down": 2**64 - 1, "Main.over": 0,
                   "Main.under": (2**32 - 1) * 1_000_000, "Main.s": b"LTIME#1ms", "Main.back": 2**64 - 1}


def test_an_ltime_read_through_memory_is_unsigned():
    out = _run("twincat", "u : ULINT := 16#FFFF_FFFF_FFFF_FFFF; p : POINTER TO LTIME; x : LTIME;",
               "p := ADR(u); x := p^;", ["x"])
    assert out == {"Main.x": 2**64 - 1}


@pytest.mark.parametrize("dialect, literal", [("twincat", "T#49D17H2M47S296MS"), ("codesys", "T#-1ms"),
                                              ("twincat", "LTIME#213503D23H34M33S709MS551US616NS")])
def test_a_duration_outside_the_unsigned_range_is_refused(dialect, literal):
    rc, err = check_text(f"PROGRAM Main VAR x : LTIME; END_VAR x := {literal}; END_PROGRAM\n", dialect=dialect)
    assert rc == 1 and "out of range" in err and "in this dialect" in err


@pytest.mark.parametrize("dialect", ["sysmac", "iec"])
def test_sysmac_and_iec_keep_signed_64_bit_nanoseconds(dialect):
    rc, err = check_text(f"PROGRAM Main VAR x : LTIME := {LTIME_MAX}; END_VAR END_PROGRAM\n", dialect=dialect)
    assert rc == 1 and "±106751d23h47m16s854ms775us807ns" in err
    out = _run(dialect, "d : LTIME; s : STRING; t : TIME;",
               "d := LTIME#0ns - LTIME#1ns; s := LTIME_TO_STRING(LTIME#1ms); t := T#0ms - T#1ms;", ["d", "s", "t"])
    assert out == {"Main.d": -1, "Main.s": b"LT#1ms", "Main.t": -1_000_000}
