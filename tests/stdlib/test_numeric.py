"""Numeric, arithmetic, selection and bit functions (IEC 61131-3; results in the result type)."""

from __future__ import annotations

import math

import pytest

from stdlib_helpers import call, make_ctx
from stvm.runtime.values import FunctionError, STFault
from stvm.semantics.types import BOOL, BYTE, DINT, INT, LINT, LREAL, REAL, STRING, TIME, UINT, WORD
from stvm.stdlib.registry import NATIVE_FUNCTIONS
from stvm.stdlib.typeops import to_real32


def rule(name, *arg_types):
    return NATIVE_FUNCTIONS[name.upper()].result_rule(arg_types)


@pytest.mark.parametrize(("name", "result_type", "args", "result"), [
    ("ABS", INT, (-5,), 5),
    ("ABS", INT, (-32768,), -32768),            # wraps, as the INT result must
    ("ABS", REAL, (-2.5,), 2.5),
    ("SQRT", REAL, (2.0,), to_real32(math.sqrt(2))),
    ("SQRT", LREAL, (2.0,), math.sqrt(2)),
    ("LN", LREAL, (math.e,), 1.0),
    ("LOG", LREAL, (1000.0,), 3.0),
    ("EXP", LREAL, (0.0,), 1.0),
    ("SIN", LREAL, (0.0,), 0.0),
    ("COS", LREAL, (0.0,), 1.0),
    ("TAN", LREAL, (0.0,), 0.0),
    ("ASIN", LREAL, (1.0,), math.pi / 2),
    ("ACOS", LREAL, (1.0,), 0.0),
    ("ATAN", REAL, (1.0,), to_real32(math.pi / 4)),
    ("EXPT", REAL, (2.0, 10), 1024.0),
    ("EXPT", LREAL, (2.0, -1), 0.5),
    ("ADD", INT, (32767, 1), -32768),
    ("ADD", DINT, (1, 2, 3, 4), 10),
    ("ADD", TIME, (1_000, 2_000), 3_000),
    ("MUL", INT, (300, 300), 24464),            # 90000 wrapped into INT
    ("SUB", UINT, (0, 1), 65535),
    ("DIV", INT, (-7, 2), -3),                  # toward zero
    ("DIV", INT, (7, -2), -3),
    ("DIV", REAL, (1.0, 4.0), 0.25),
    ("MAX", INT, (3, 9, -2), 9),
    ("MIN", INT, (3, 9, -2), -2),
    ("MAX", REAL, (3, 2.5), 3.0),
    ("MAX", STRING, (b"AB", b"B"), b"B"),
    ("LIMIT", INT, (0, 50, 10), 10),
    ("LIMIT", INT, (0, -5, 10), 0),
    ("LIMIT", INT, (0, 5, 10), 5),
    ("SEL", INT, (False, 1, 2), 1),
    ("SEL", INT, (True, 1, 2), 2),
    ("MUX", INT, (2, 10, 11, 12, 13), 12),
    ("MOVE", WORD, (0x1234,), 0x1234),
    ("TRUNC", DINT, (-3.55,), -3),
    ("TRUNC", DINT, (3.99,), 3),
    ("Round", DINT, (2.5,), 2),                 # W502 2-284: ties to even
    ("Round", DINT, (-1.5,), -2),
    ("Round", DINT, (1.6,), 2),
    ("RoundUp", DINT, (1.4,), 2),
    ("RoundUp", DINT, (-1.4,), -2),
    ("RoundUp", DINT, (2.0,), 2),
    ("SHL", BYTE, (0x81, 1), 0x02),
    ("SHL", BYTE, (0x81, 8), 0),
    ("SHL", WORD, (1, 15), 0x8000),
    ("SHR", BYTE, (0x81, 1), 0x40),
    ("SHR", BYTE, (0x81, 9), 0),
    ("ROL", BYTE, (0x81, 1), 0x03),
    ("ROL", BYTE, (0x81, 9), 0x03),
    ("ROR", BYTE, (0x81, 1), 0xC0),
    ("ROR", WORD, (0x0001, 4), 0x1000),
    ("ROL", BOOL, (True, 3), True),
])
def test_function(name, result_type, args, result):
    assert call(name, make_ctx(), *args, result_type=result_type) == result


def test_ieee_special_values():
    ctx = make_ctx()
    assert math.isnan(call("SQRT", ctx, -1.0, result_type=REAL))
    assert call("LN", ctx, 0.0, result_type=LREAL) == -math.inf
    assert call("EXP", ctx, 1000.0, result_type=REAL) == math.inf
    assert call("DIV", ctx, 1.0, 0.0, result_type=REAL) == math.inf
    assert math.isnan(call("DIV", ctx, 0.0, 0.0, result_type=REAL))
    assert call("TRUNC", ctx, math.nan, result_type=DINT) == 0


def test_integer_division_by_zero():
    with pytest.raises(STFault):
        call("DIV", make_ctx(), 1, 0, result_type=INT)
    assert call("DIV", make_ctx(int_div_zero="zero"), 1, 0, result_type=INT) == 0


def test_mux_out_of_range_is_an_instruction_error():
    with pytest.raises(FunctionError):
        call("MUX", make_ctx(), 3, 1, 2, result_type=INT)
    with pytest.raises(FunctionError):
        call("MUX", make_ctx(), -1, 1, 2, result_type=INT)


def test_negative_shift_is_an_instruction_error():
    with pytest.raises(FunctionError):
        call("SHL", make_ctx(), 1, -1, result_type=BYTE)


def test_move_copies_arrays():
    source = [1, 2, [3]]
    copied = call("MOVE", make_ctx(), source, result_type=None)
    assert copied == source and copied is not source and copied[2] is not source[2]


def test_result_rules():
    assert rule("TRUNC", REAL) == DINT
    assert rule("TRUNC", LREAL) == LINT
    assert rule("SHL", BYTE, DINT) == BYTE
    assert rule("EXPT", REAL, LINT) == REAL
    assert rule("MUX", DINT, INT, UINT) == UINT          # signed + unsigned of one rank
    assert rule("MUX", LINT, INT, REAL) == REAL
    assert rule("SEL", BOOL, INT, DINT) == DINT
