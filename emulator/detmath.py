"""Machine-independent arithmetic for everything that decides a time stamp (issue 17).

The emulator's motion durations come from kinematics (inverse kinematics → joint distances →
trapezoid timing, rounded to whole nanoseconds). With numpy's BLAS/LAPACK kernels (chosen per
CPU: FMA or not, AVX-512 or not) and the C library's sin/cos (FMA and non-FMA builds), the same
script gave durations 0.35 ns apart on two machines, and a duration 0.0002 ns from a rounding
boundary came out 1 ns different in two golden frames.

Everything here uses only IEEE-754 binary64 operations that are exactly rounded on every
platform Python runs on (+ - * / and sqrt, each one rounding; CPython never fuses a*b+c), in a
fixed order, so the results are bit-identical on x86-64 (any SIMD level) and ARM:

* sin, cos, atan2, asin, acos: argument reduction with a three-part pi/2 (exact products for
  |x| < 2**20 * pi/2, an exact integer reduction beyond) and Taylor polynomials whose
  coefficients are rounded from exact fractions. Accuracy: a few ulp (the robot model needs far
  less; determinism is the point).
* small-matrix products, dot products, norms and a 6x6 solve with a fixed summation order (no
  BLAS), on numpy arrays in and out so that callers keep their types.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Sequence

import numpy as np

# ---------------------------------------------------------------- constants from exact integers


def _pi_fixed(bits: int) -> int:
    """floor(pi * 2**bits), by Machin's formula in integer arithmetic (no floating point)."""
    guard = bits + 20
    one = 1 << guard

    def arctan_inv(n: int) -> int:   # arctan(1/n) * 2**guard
        total, term, k, sign = 0, one // n, 1, 1
        n2 = n * n
        while term:
            total += sign * (term // k)
            term //= n2
            k += 2
            sign = -sign
        return total

    return (16 * arctan_inv(5) - 4 * arctan_inv(239)) >> 20


_PI_BITS = 1200
_PI_INT = _pi_fixed(_PI_BITS)                # pi = _PI_INT / 2**_PI_BITS (to 2**-1200)
_PIO2_INT = _PI_INT >> 1                     # pi/2 at the same scale (exact halving)


def _float_of(numerator: int, exponent: int, bits: int = 53) -> float:
    """numerator * 2**exponent rounded to `bits` significant bits (half-even), as a float."""
    if numerator == 0:
        return 0.0
    shift = max(0, numerator.bit_length() - bits)
    mantissa, rest = divmod(numerator, 1 << shift)
    half = 1 << (shift - 1) if shift else 0
    if shift and (rest > half or (rest == half and mantissa & 1)):
        mantissa += 1
    return math.ldexp(mantissa, shift + exponent)


PI = _float_of(_PI_INT, -_PI_BITS)
assert PI == math.pi
HALF_PI = PI / 2
RAD_PER_DEG = PI / 180.0
DEG_PER_RAD = 180.0 / PI
_TWO_OVER_PI = _float_of((1 << (2 * _PI_BITS)) // _PIO2_INT, -_PI_BITS)

# pi/2 in three parts of 33, 33 and 53 bits: n * part is exact for |n| < 2**20
_PIO2_1 = _float_of(_PIO2_INT, -_PI_BITS, 33)
_rest = _PIO2_INT - int(Fraction(_PIO2_1) * (1 << _PI_BITS))
_PIO2_2 = _float_of(_rest, -_PI_BITS, 33)
_rest -= int(Fraction(_PIO2_2) * (1 << _PI_BITS))
_PIO2_3 = _float_of(_rest, -_PI_BITS, 53)
_MEDIUM = 1_000_000.0                        # below 2**20 * pi/2: the three-part reduction

# Taylor coefficients 1/(2k+1)! and 1/(2k)!, alternating, each the float nearest the fraction
_SIN = [float(Fraction((-1) ** k, math.factorial(2 * k + 1))) for k in range(1, 12)]
_COS = [float(Fraction((-1) ** k, math.factorial(2 * k))) for k in range(1, 12)]
_ATAN = [float(Fraction((-1) ** k, 2 * k + 1)) for k in range(1, 12)]


def _reduce(x: float) -> tuple[int, float]:
    """(n, r) with x = n * pi/2 + r, |r| <= pi/4 (about)."""
    if abs(x) <= _MEDIUM:
        n = math.floor(x * _TWO_OVER_PI + 0.5)
        r = ((x - n * _PIO2_1) - n * _PIO2_2) - n * _PIO2_3
        return n, r
    # exact: x = p / q with q a power of two; n = round(x / (pi/2)), r = x - n*pi/2
    p, q = x.as_integer_ratio()
    scaled = p << _PI_BITS                   # x * 2**_PI_BITS * q
    den = q * _PIO2_INT
    n = (2 * scaled + den) // (2 * den)
    remainder = scaled - n * den             # r * q * 2**_PI_BITS
    return n, remainder / (q << _PI_BITS)    # int / int: correctly rounded


def _sin_kernel(r: float) -> float:
    z = r * r
    poly = _SIN[-1]
    for c in reversed(_SIN[:-1]):
        poly = poly * z + c
    return r + r * z * poly


def _cos_kernel(r: float) -> float:
    z = r * r
    poly = _COS[-1]
    for c in reversed(_COS[:-1]):
        poly = poly * z + c
    return 1.0 + z * poly


def sin(x: float) -> float:
    x = float(x)
    if not math.isfinite(x):
        return math.nan
    n, r = _reduce(x)
    quadrant = n & 3
    if quadrant == 0:
        return _sin_kernel(r)
    if quadrant == 1:
        return _cos_kernel(r)
    if quadrant == 2:
        return -_sin_kernel(r)
    return -_cos_kernel(r)


def cos(x: float) -> float:
    x = float(x)
    if not math.isfinite(x):
        return math.nan
    n, r = _reduce(x)
    quadrant = n & 3
    if quadrant == 0:
        return _cos_kernel(r)
    if quadrant == 1:
        return -_sin_kernel(r)
    if quadrant == 2:
        return -_cos_kernel(r)
    return _sin_kernel(r)


def sincos(x: float) -> tuple[float, float]:
    """(sin(x), cos(x)) with one argument reduction: the same bits as the two calls."""
    x = float(x)
    if not math.isfinite(x):
        return math.nan, math.nan
    n, r = _reduce(x)
    quadrant = n & 3
    if quadrant == 0:
        return _sin_kernel(r), _cos_kernel(r)
    if quadrant == 1:
        return _cos_kernel(r), -_sin_kernel(r)
    if quadrant == 2:
        return -_sin_kernel(r), -_cos_kernel(r)
    return -_cos_kernel(r), _sin_kernel(r)


def _atan_small(t: float) -> float:
    """atan for 0 <= t <= 1: halve the angle until t < 0.1, then the series."""
    halvings = 0
    while t > 0.1:
        t = t / (1.0 + math.sqrt(1.0 + t * t))   # tan(a/2) = tan a / (1 + sec a)
        halvings += 1
    z = t * t
    poly = _ATAN[-1]
    for c in reversed(_ATAN[:-1]):
        poly = poly * z + c
    return (t + t * z * poly) * (1 << halvings)


def atan(x: float) -> float:
    x = float(x)
    if math.isnan(x):
        return math.nan
    if x < 0:
        return -atan(-x)
    if x > 1.0:
        if math.isinf(x):
            return HALF_PI
        return HALF_PI - _atan_small(1.0 / x)
    return _atan_small(x)


def atan2(y: float, x: float) -> float:
    y, x = float(y), float(x)
    if math.isnan(x) or math.isnan(y):
        return math.nan
    if x == 0.0:
        if y > 0:
            return HALF_PI
        if y < 0:
            return -HALF_PI
        return math.copysign(PI if math.copysign(1.0, x) < 0 else 0.0, y)
    if math.isinf(x) or math.isinf(y):
        return math.atan2(y, x)   # exact special values (multiples of pi/4), the same everywhere
    if abs(y) > abs(x):
        angle = HALF_PI - atan(abs(x) / abs(y))
    else:
        angle = atan(abs(y) / abs(x))
    if x < 0:
        angle = PI - angle
    return angle if math.copysign(1.0, y) > 0 else -angle


def asin(x: float) -> float:
    x = float(x)
    if not -1.0 <= x <= 1.0:
        return math.nan
    return atan2(x, math.sqrt((1.0 - x) * (1.0 + x)))


def acos(x: float) -> float:
    x = float(x)
    if not -1.0 <= x <= 1.0:
        return math.nan
    return atan2(math.sqrt((1.0 - x) * (1.0 + x)), x)


def radians(x: float) -> float:
    return float(x) * RAD_PER_DEG


def degrees(x: float) -> float:
    return float(x) * DEG_PER_RAD


# ---------------------------------------------------------------- small linear algebra


def dot(a: Sequence[float], b: Sequence[float]) -> float:
    total = 0.0
    for x, y in zip(a, b):
        total += float(x) * float(y)
    return total


def norm(a: Sequence[float]) -> float:
    return math.sqrt(dot(a, a))


def cross(a: Sequence[float], b: Sequence[float]) -> np.ndarray:
    a0, a1, a2 = (float(v) for v in a)
    b0, b1, b2 = (float(v) for v in b)
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a @ b for small matrices (and matrix @ vector), summed left to right."""
    left = np.asarray(a, dtype=float).tolist()
    right = np.asarray(b, dtype=float).tolist()
    if right and not isinstance(right[0], list):     # matrix @ vector
        return np.array([_dot_floats(row, right) for row in left])
    columns = list(zip(*right))
    inner = len(right)
    # the rotations and poses (3x3, 4x4): the sums written out, in the loop's order
    # (((0.0 + p0) + p1) + p2) + p3, so the bits are _dot_floats's, without a call per element
    if inner == 4 and all(len(row) == 4 for row in left):
        return np.array([[0.0 + r0 * c0 + r1 * c1 + r2 * c2 + r3 * c3 for c0, c1, c2, c3 in columns]
                         for r0, r1, r2, r3 in left])
    if inner == 3 and all(len(row) == 3 for row in left):
        return np.array([[0.0 + r0 * c0 + r1 * c1 + r2 * c2 for c0, c1, c2 in columns]
                         for r0, r1, r2 in left])
    return np.array([[_dot_floats(row, col) for col in columns] for row in left])


def _dot_floats(a: Sequence[float], b: Sequence[float]) -> float:
    """`dot` of two sequences of Python floats (what `tolist()` of a float array holds): the
    same products and sums in the same order, without `dot`'s float() conversions."""
    total = 0.0
    for x, y in zip(a, b):
        total += x * y
    return total


def trace3(m: np.ndarray) -> float:
    return float(m[0, 0]) + float(m[1, 1]) + float(m[2, 2])


def rigid_inverse(t: np.ndarray) -> np.ndarray:
    """The inverse of a 4x4 rigid transform [R p; 0 1]: [R^T, -R^T p; 0 1] (no LAPACK)."""
    rot_t = np.asarray(t, dtype=float)[:3, :3].T.copy()
    out = np.eye(4)
    out[:3, :3] = rot_t
    out[:3, 3] = -matmul(rot_t, t[:3, 3])
    return out


def solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """x with a @ x = b (Gaussian elimination, partial pivoting, fixed order)."""
    return np.array(solve_lists(np.asarray(a, dtype=float).tolist(), [float(v) for v in b]))


def solve_lists(m: list[list[float]], rhs: list[float]) -> list[float]:
    """`solve` on lists of Python floats (changed in place), returning a list."""
    size = len(m)
    for col in range(size):
        pivot = max(range(col, size), key=lambda r: abs(m[r][col]))
        if m[pivot][col] == 0.0:
            raise np.linalg.LinAlgError("singular matrix")
        if pivot != col:
            m[col], m[pivot] = m[pivot], m[col]
            rhs[col], rhs[pivot] = rhs[pivot], rhs[col]
        row_c = m[col]
        for r in range(col + 1, size):
            factor = m[r][col] / row_c[col]
            if factor != 0.0:
                row_r = m[r]
                for k in range(col, size):
                    row_r[k] -= factor * row_c[k]
                rhs[r] -= factor * rhs[col]
    x = [0.0] * size
    for r in range(size - 1, -1, -1):
        total = rhs[r]
        row = m[r]
        for k in range(r + 1, size):
            total -= row[k] * x[k]
        x[r] = total / row[r]
    return x
