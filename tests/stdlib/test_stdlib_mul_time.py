"""MUL_TIME (stvm/stdlib/timefns.py): a whole factor takes a shortcut (the V2 library's CBT_Connect
multiplies T#1s by its time-out every scan); the result must be the exact one, nearest ns, as
for any other factor."""

from __future__ import annotations

import random
from fractions import Fraction

import pytest

from stvm.runtime.values import FunctionError
from stvm.semantics.types import LINT
from stvm.stdlib.timefns import mul_time


def exact(duration: int, factor: float) -> int:
    return LINT.wrap(round(Fraction(duration) * Fraction(factor)))


@pytest.mark.parametrize("duration, factor", [
    (1_000_000_000, 10.0), (1_000_000_000, 0.0), (1_000_000_000, -3.0), (-7, 2.0),
    (1_000_000_000, 2.5), (3, 0.5), (5, 0.5), (2**62, 4.0), (2**62, 1e30), (1, 2.0**60),
])
def test_mul_time_is_the_nearest_ns_of_the_exact_product(duration, factor):
    assert mul_time(None, duration, factor) == exact(duration, factor)


def test_mul_time_whole_and_fractional_factors_agree_with_the_exact_product():
    rng = random.Random(33)
    for _ in range(2000):
        duration = rng.randrange(-2**63, 2**63)
        factor = float(rng.randrange(-10**6, 10**6)) if rng.random() < 0.5 else rng.uniform(-1e6, 1e6)
        assert mul_time(None, duration, factor) == exact(duration, factor)


def test_mul_time_refuses_a_factor_that_is_not_finite():
    with pytest.raises(FunctionError):
        mul_time(None, 1, float("inf"))
    with pytest.raises(FunctionError):
        mul_time(None, 1, float("nan"))
