"""Differential test (byterun style): random ST arithmetic evaluated by stvm and by a Python model.

The model follows sysmac.md 2:
* integer results take the highest-ranked operand type (1 USINT/SINT/BYTE, 2 UINT/INT/WORD,
  4 DINT/UDINT/DWORD, 6 LINT/ULINT/LWORD); of one rank signed+unsigned → unsigned (a bit string
  wins over an unsigned integer: same values). Operands are converted to that type and the result
  wraps at its width *before* any widening for the assignment; comparisons compare in that type.
* integer `/` truncates toward zero, `MOD` has the dividend's sign, both fault on 0.
* REAL is IEEE binary32 (numpy.float32) after every operation, LREAL binary64.
* mixed integer/real: stvm's documented Choice (semantics/body.py `real_for`, sysmac.md 2 ranks
  REAL below DINT): an 8/16-bit integer with REAL computes in REAL, a 32/64-bit integer with a
  real in LREAL; anything with LREAL in LREAL.
Values are set through the API before the first scan, one scan runs, results are read back.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

import stvm
from core_helpers import load_st

INT_TYPES = {  # name: (bits, signed, bitstring)
    "SINT": (8, True, False), "INT": (16, True, False), "DINT": (32, True, False), "LINT": (64, True, False),
    "USINT": (8, False, False), "UINT": (16, False, False), "UDINT": (32, False, False),
    "ULINT": (64, False, False),
    "BYTE": (8, False, True), "WORD": (16, False, True), "DWORD": (32, False, True), "LWORD": (64, False, True),
}
REAL_TYPES = {"REAL": 32, "LREAL": 64}
RANK = {8: 1, 16: 2, 32: 4, 64: 6}
NON_BITSTRING = [t for t, (_, _, bs) in INT_TYPES.items() if not bs]


class Fault(Exception):
    pass


def is_int(t: str) -> bool:
    return t in INT_TYPES


def wrap(v: int, t: str) -> int:
    bits, signed, _ = INT_TYPES[t]
    v &= (1 << bits) - 1
    if signed and v >= 1 << (bits - 1):
        v -= 1 << bits
    return v


def f32(x) -> float:
    with np.errstate(all="ignore"):
        return float(np.float32(x))


def common(a: str, b: str) -> str:
    if is_int(a) and is_int(b):
        (ba, sa, _bsa), (bb, _sb, _bsb) = INT_TYPES[a], INT_TYPES[b]
        if RANK[ba] != RANK[bb]:
            return a if RANK[ba] > RANK[bb] else b
        if a == b:
            return a
        for cand in (a, b):
            if INT_TYPES[cand][2]:
                return cand
        return a if not sa else b
    if "LREAL" in (a, b):
        return "LREAL"
    if a == b == "REAL":
        return "REAL"
    other = a if is_int(a) else b
    return "REAL" if INT_TYPES[other][0] <= 16 else "LREAL"


def convert(v, src: str, dst: str):
    if is_int(dst):
        return wrap(v, dst)
    if dst == "REAL":
        return f32(v) if is_int(src) else v
    return float(v)


def ieee_div(a: float, b: float, t: str) -> float:
    with np.errstate(all="ignore"):
        if t == "REAL":
            return float(np.float32(a) / np.float32(b))
        return float(np.float64(a) / np.float64(b))


def arith(op: str, a, b, t: str):
    if is_int(t):
        if op == "+":
            return wrap(a + b, t)
        if op == "-":
            return wrap(a - b, t)
        if op == "*":
            return wrap(a * b, t)
        if b == 0:
            raise Fault()
        q = abs(a) // abs(b)
        q = q if (a < 0) == (b < 0) else -q
        return wrap(q, t) if op == "/" else wrap(a - b * q, t)
    if op == "/":
        return ieee_div(a, b, t)
    with np.errstate(all="ignore"):
        if t == "REAL":
            x, y = np.float32(a), np.float32(b)
        else:
            x, y = np.float64(a), np.float64(b)
        r = x + y if op == "+" else x - y if op == "-" else x * y
    return float(r)


# ---------------------------------------------------------------- expression trees
@dataclass(frozen=True)
class Var:
    name: str
    ty: str

    def text(self) -> str:
        return self.name

    def eval(self, env):
        return env[self.name]


@dataclass(frozen=True)
class Lit:
    ty: str
    value: object
    src: str

    def text(self) -> str:
        return f"{self.ty}#{self.src}"

    def eval(self, env):
        return self.value


@dataclass(frozen=True)
class Neg:
    operand: object
    ty: str

    def text(self) -> str:
        return f"(-{self.operand.text()})"

    def eval(self, env):
        v = self.operand.eval(env)
        return wrap(-v, self.ty) if is_int(self.ty) else -v


@dataclass(frozen=True)
class Bin:
    op: str
    left: object
    right: object
    ty: str

    def text(self) -> str:
        return f"({self.left.text()} {self.op} {self.right.text()})"

    def eval(self, env):
        a = convert(self.left.eval(env), self.left.ty, self.ty)
        b = convert(self.right.eval(env), self.right.ty, self.ty)
        return arith(self.op, a, b, self.ty)


CMP = {"=": lambda a, b: a == b, "<>": lambda a, b: a != b, "<": lambda a, b: a < b,
       ">": lambda a, b: a > b, "<=": lambda a, b: a <= b, ">=": lambda a, b: a >= b}

REAL_LITS = {"REAL": ["0.5", "1.5", "2.0", "0.1", "3.25", "-2.5", "1.0e10", "1.0e-10"],
             "LREAL": ["0.5", "1.5", "0.1", "-7.25", "1.0e300", "1.0e-300"]}


def value_strategy(t: str):
    if is_int(t):
        bits, signed, _ = INT_TYPES[t]
        lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
        return st.integers(lo, hi)
    if t == "REAL":
        return st.floats(width=32, allow_nan=False, allow_infinity=False)
    return st.floats(allow_nan=False, allow_infinity=False)


@st.composite
def literal(draw, pool):
    t = draw(st.sampled_from(pool))
    if is_int(t):
        bits, signed, _ = INT_TYPES[t]
        lo = -100 if signed else 0
        v = draw(st.integers(lo, 100) | st.sampled_from([(1 << (bits - 1)) - 1 if signed else (1 << bits) - 1]))
        return Lit(t, v, str(v))
    src = draw(st.sampled_from(REAL_LITS[t]))
    return Lit(t, f32(float(src)) if t == "REAL" else float(src), src)


@st.composite
def expression(draw, variables, pool, depth):
    if depth == 0 or draw(st.integers(0, 3)) == 0:
        if draw(st.integers(0, 4)) == 0:
            return draw(literal(pool))
        return draw(st.sampled_from(variables))
    kind = draw(st.integers(0, 9))
    if kind == 0:
        inner = draw(expression(variables, pool, depth - 1))
        if is_int(inner.ty) and not INT_TYPES[inner.ty][1]:
            return inner                     # negating an unsigned value: left out (sign rules unclear)
        return Neg(inner, inner.ty)
    left = draw(expression(variables, pool, depth - 1))
    right = draw(expression(variables, pool, depth - 1))
    op = draw(st.sampled_from(["+", "-", "*", "/", "MOD"]))
    ty = common(left.ty, right.ty)
    if op == "MOD" and not is_int(ty):
        op = "+"
    return Bin(op, left, right, ty)


def widenings(t: str) -> list[str]:
    if t == "REAL":
        return ["REAL", "LREAL"]
    if t == "LREAL":
        return ["LREAL"]
    bits, signed, bitstring = INT_TYPES[t]
    if bitstring:
        return [n for n, (b, s, bs) in INT_TYPES.items() if bs and b >= bits]
    out = [n for n, (b, s, bs) in INT_TYPES.items() if not bs and s == signed and b > bits]
    same_size = [n for n, (b, s, bs) in INT_TYPES.items() if not bs and b == bits]   # keeps the bits
    return same_size + out + ["LREAL"]


@st.composite
def program(draw):
    domain = draw(st.sampled_from(["int", "mixed"]))
    pool = list(INT_TYPES) if domain == "int" else NON_BITSTRING + ["REAL", "LREAL", "REAL", "LREAL"]
    n_vars = draw(st.integers(2, 5))
    variables = [Var(f"v{i}", draw(st.sampled_from(pool))) for i in range(n_vars)]
    values = {v.name: draw(value_strategy(v.ty)) for v in variables}
    statements = []
    for k in range(draw(st.integers(1, 4))):
        e = draw(expression(variables, pool, 3))
        if draw(st.integers(0, 3)) == 0:
            e2 = draw(expression(variables, pool, 2))
            if is_int(e.ty) != is_int(e2.ty) and (INT_TYPES.get(e.ty, (0, 0, False))[2]
                                                 or INT_TYPES.get(e2.ty, (0, 0, False))[2]):
                e2 = e
            statements.append(("cmp", f"c{k}", "BOOL", draw(st.sampled_from(list(CMP))), e, e2))
        else:
            target = draw(st.sampled_from(widenings(e.ty)))
            statements.append(("assign", f"r{k}", target, None, e, None))
    return variables, values, statements


def source_of(variables, statements) -> str:
    decls = [f"  {v.name} : {v.ty};" for v in variables]
    body = []
    for kind, name, ty, op, e, e2 in statements:
        decls.append(f"  {name} : {ty};")
        body.append(f"{name} := {e.text()} {op} {e2.text()};" if kind == "cmp" else f"{name} := {e.text()};")
    return "PROGRAM Main\nVAR\n" + "\n".join(decls) + "\nEND_VAR\n" + "\n".join(body) + "\nEND_PROGRAM\n"


def reference(values, statements):
    """[(name, expected)] for the statements before a fault, and whether a fault happens."""
    out = []
    for kind, name, ty, op, e, e2 in statements:
        try:
            if kind == "cmp":
                t = common(e.ty, e2.ty)
                a, b = convert(e.eval(values), e.ty, t), convert(e2.eval(values), e2.ty, t)
                out.append((name, CMP[op](a, b)))
            else:
                out.append((name, convert(e.eval(values), e.ty, ty)))
        except Fault:
            return out, True
    return out, False


def same(a, b) -> bool:
    if isinstance(a, float) or isinstance(b, float):
        if math.isnan(a) and math.isnan(b):
            return True
        return a == b
    return a == b and type(a) is type(b)


def generated_main(project) -> str:
    src = project.lowered.source
    cls = project.lowered.classes["main"]
    m = re.search(rf"^class {cls}\b.*?(?=^\S)", src + "\nEOF", re.S | re.M)
    return m.group(0) if m else src


@settings(max_examples=100, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(program())
def test_arithmetic_matches_the_reference_model(prog):
    variables, values, statements = prog
    text = source_of(variables, statements)
    note(text)
    note(f"values: {values}")
    project = load_st(text)
    note(generated_main(project))
    vm = project.start()
    for name, value in values.items():
        vm[f"Main.{name}"] = value
    expected, faults = reference(values, statements)
    if faults:
        with pytest.raises(stvm.RuntimeFault):
            vm.scan()
    else:
        vm.scan()
    for name, want in expected:
        got = vm[f"Main.{name}"]
        assert same(got, want), f"{name}: stvm {got!r}, model {want!r}"


# ---------------------------------------------------------------- a few fixed points of the model
@pytest.mark.parametrize(("a", "b", "t"), [("SINT", "USINT", "USINT"), ("INT", "UDINT", "UDINT"),
                                           ("BYTE", "USINT", "BYTE"), ("LINT", "ULINT", "ULINT"),
                                           ("INT", "REAL", "REAL"), ("DINT", "REAL", "LREAL"),
                                           ("USINT", "LREAL", "LREAL"), ("WORD", "DINT", "DINT")])
def test_model_result_types(a, b, t):
    assert common(a, b) == common(b, a) == t


def test_model_wraps_before_widening():
    e = Bin("+", Lit("UDINT", 2**32 - 1, "16#FFFF_FFFF"), Lit("DINT", 1, "1"), "UDINT")
    assert convert(e.eval({}), "UDINT", "LINT") == 0
