"""Values as IEC literals (`--print`, `vm.format`): exactly the forms issue 3 lists."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from core_helpers import load_st

SOURCE = """
TYPE
  Color : (Red, Green, Blue);
  Inner : STRUCT n : INT; f : BOOL; END_STRUCT;
  Rec : STRUCT a : INT; b : STRING[8]; in : Inner; END_STRUCT;
END_TYPE
FUNCTION_BLOCK Blk
VAR_INPUT i : INT; END_VAR
VAR_OUTPUT q : BOOL; END_VAR
q := i > 0;
END_FUNCTION_BLOCK
VAR_GLOBAL gl : INT := -3; END_VAR
PROGRAM Main
VAR
  bt, bf : BOOL; si : SINT; i : INT; ul : ULINT; li : LINT; byt : BYTE; lw : LWORD;
  r : REAL; l : LREAL; t : TIME; d : DATE; tod1 : TOD; dt1 : DT;
  s : STRING; c : Color; rec : Rec; arr : ARRAY[1..3] OF INT; m : ARRAY[1..2, 1..2] OF INT;
  sa : ARRAY[0..1] OF Inner; strs : ARRAY[1..2] OF STRING[4]; blk : Blk; cs : ARRAY[1..2] OF Color;
END_VAR
blk(i := 1);
END_PROGRAM
"""


@pytest.fixture(scope="module")
def project():
    return load_st(SOURCE)


@pytest.fixture
def vm(project):
    return project.start()


@pytest.mark.parametrize(("path", "value", "text"), [
    ("Main.bt", True, "TRUE"),
    ("Main.bf", False, "FALSE"),
    ("Main.si", -128, "-128"),
    ("Main.i", 1234, "1234"),
    ("Main.ul", 2**64 - 1, "18446744073709551615"),
    ("Main.li", -2**63, "-9223372036854775808"),
    ("Main.byt", 255, "255"),                         # bit strings print in decimal too
    ("Main.lw", 2**64 - 1, "18446744073709551615"),
    ("Main.r", 1.5, "1.5"),
    ("Main.r", 0.1, "0.1"),
    ("Main.r", -2.25, "-2.25"),
    ("Main.l", 0.1, "0.1"),
    ("Main.l", 1.0, "1.0"),
    ("Main.t", 1_500_000_000, "T#1s500ms"),
    ("Main.t", 0, "T#0s"),
    ("Main.t", -1_500_000_000, "T#-1s500ms"),
    ("Main.t", 500_000, "T#500us"),
    ("Main.t", ((((1 * 24 + 2) * 60 + 3) * 60 + 4) * 1000 + 5) * 1_000_000 + 6007, "T#1d2h3m4s5ms6us7ns"),
    ("Main.s", b"abc", "'abc'"),
    ("Main.s", b"", "''"),
    ("Main.s", b"it's $5\r\n\t\x0c", "'it$'s $$5$R$L$T$P'"),
    ("Main.c", 1, "Color#Green"),
    ("gl", -3, "-3"),
])
def test_scalar_literals(vm, path, value, text):
    vm[path] = value
    assert vm.format(path) == text


def test_non_printable_bytes_use_hex_escapes(vm):
    vm["Main.s"] = b"a\x01\x7f"
    text = vm.format("Main.s")
    assert re.fullmatch(r"'a\$01\$7[fF]'", text)


def test_date_time_of_day_date_and_time(vm):
    vm["Main.d"] = 1709164800 * 10**9
    vm["Main.tod1"] = (12 * 3600 + 34 * 60 + 56) * 10**9 + 789_000_000
    vm["Main.dt1"] = 1704164645 * 10**9
    assert vm.format("Main.d") == "D#2024-02-29"
    assert vm.format("Main.tod1") == "TOD#12:34:56.789"
    assert vm.format("Main.dt1") == "DT#2024-01-02-03:04:05"


def test_struct_array_and_fb_forms(vm):
    vm["Main.rec.a"] = 1
    vm["Main.rec.b"] = "x"
    vm["Main.arr[1]"] = 1
    vm["Main.arr[2]"] = 2
    vm["Main.arr[3]"] = 3
    vm["Main.m[2, 1]"] = 5
    vm["Main.strs[2]"] = "q'"
    vm["Main.cs[2]"] = "Color#Blue"
    vm.scan()
    assert vm.format("Main.rec") == "(a := 1, b := 'x', in := (n := 0, f := FALSE))"
    assert vm.format("Main.rec.in") == "(n := 0, f := FALSE)"
    assert vm.format("Main.arr") == "[1, 2, 3]"
    assert vm.format("Main.arr[2]") == "2"
    assert vm.format("Main.m") == "[[0, 0], [5, 0]]"
    assert vm.format("Main.sa") == "[(n := 0, f := FALSE), (n := 0, f := FALSE)]"
    assert vm.format("Main.strs") == "['', 'q$'']"
    assert vm.format("Main.cs") == "[Color#Red, Color#Blue]"
    assert vm.format("Main.blk.q") == "TRUE"


# ---------------------------------------------------------------- REAL / LREAL round trip
def _roundtrip_f32(text: str) -> float:
    return float(np.float32(float(text)))


@settings(max_examples=100, deadline=None, database=None)
@given(st.floats(width=32, allow_nan=False, allow_infinity=False))
def test_real_text_round_trips_to_the_same_float32(project, x):
    vm = project.start()
    vm["Main.r"] = x
    text = vm.format("Main.r")
    assert _roundtrip_f32(text) == vm["Main.r"]
    assert math.copysign(1.0, _roundtrip_f32(text)) == math.copysign(1.0, vm["Main.r"])


@settings(max_examples=100, deadline=None, database=None)
@given(st.floats(allow_nan=False, allow_infinity=False))
def test_lreal_text_round_trips(project, x):
    vm = project.start()
    vm["Main.l"] = x
    assert float(vm.format("Main.l")) == x


def test_real_prints_float32_digits_not_the_double_expansion(vm):
    vm["Main.r"] = 0.1                           # 0.100000001490116… as a double
    assert vm.format("Main.r") == "0.1"
    vm["Main.r"] = 16777217.0                    # rounds to 16777216 in float32
    assert _roundtrip_f32(vm.format("Main.r")) == 16777216.0
    vm["Main.r"] = 1.0 / 3.0
    text = vm.format("Main.r")
    assert len(re.sub(r"[^0-9]", "", text.split("e")[0]).lstrip("0")) >= 7   # >= 7 significant digits


IEC_REAL = re.compile(r"-?[0-9]+\.[0-9]+([eE][+-]?[0-9]+)?")


@pytest.mark.parametrize("value", [1.5, 0.1, 123456.0, 1.0, -0.0])
def test_real_text_is_an_iec_real_literal(vm, value):
    vm["Main.r"] = value
    vm["Main.l"] = value
    assert IEC_REAL.fullmatch(vm.format("Main.r"))
    assert IEC_REAL.fullmatch(vm.format("Main.l"))


@pytest.mark.parametrize("value", [1e20, 1e-20, 1e7, 3.4028234663852886e38, 1.401298464324817e-45, 1e300])
def test_real_text_with_exponent_is_an_iec_real_literal(vm, value):
    vm["Main.r"] = value
    vm["Main.l"] = value
    if math.isfinite(vm["Main.r"]):
        assert IEC_REAL.fullmatch(vm.format("Main.r")), vm.format("Main.r")
        assert _roundtrip_f32(vm.format("Main.r")) == vm["Main.r"]
    assert IEC_REAL.fullmatch(vm.format("Main.l")), vm.format("Main.l")
    assert float(vm.format("Main.l")) == value


# ---------------------------------------------------------------- printed text is accepted back by --set
@pytest.mark.parametrize(("path", "value"), [
    ("Main.bt", True), ("Main.i", -1234), ("Main.ul", 2**64 - 1), ("Main.r", 0.1), ("Main.l", -1e-300),
    ("Main.t", -1_500_000_000), ("Main.s", b"it's $5\r\n"), ("Main.c", 2), ("Main.byt", 16),
])
def test_printed_literal_is_accepted_by_set(vm, path, value):
    from stvm.semantics.literals import literal_value
    vm[path] = value
    text = vm.format(path)
    vm2 = vm.project.start()
    vm2[path] = literal_value(text, vm.type_of(path))
    assert vm2[path] == vm[path]
