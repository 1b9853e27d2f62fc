"""Machine-independent motion timing (issue 17): every time stamp is an exact integer of ns.

* The timing model of `emulator.motion.SegmentTiming` is recomputed by an independent
  reference (the module docstring's formulas in `decimal` arithmetic at 60 digits) for random
  inputs and for every segment of the golden PnP run, and the tag frames of that run are
  checked against start + duration of their segments.
* `emulator.detmath` gives bit-identical results on every IEEE-754 machine: a few bit patterns
  are pinned, and a run with other BLAS kernels and numpy SIMD levels writes the same bytes.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from decimal import ROUND_HALF_EVEN, Decimal, localcontext
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from emulator import detmath as dm
from emulator.motion import SegmentTiming

ROOT = Path(__file__).resolve().parents[2]


# ---------------------------------------------------------------- the reference


def _dec(value: Fraction) -> Decimal:
    return Decimal(value.numerator) / Decimal(value.denominator)


def _nearest(value: Decimal) -> int:
    return int(value.to_integral_value(rounding=ROUND_HALF_EVEN))


def reference_times_ns(timing: SegmentTiming) -> tuple[int, int, int, int]:
    """(duration, accel, blend, settle) ns, straight from the formulas, in decimal arithmetic."""
    with localcontext() as ctx:
        ctx.prec = 60
        ta = _dec(timing.accel_s)
        scale = _dec(timing.time_scale) * 1_000_000_000

        def trapezoid(distance: Decimal, speed: Decimal) -> Decimal:
            if distance <= 0:
                return Decimal(0)
            if ta <= 0:
                return distance / speed
            if distance >= speed * ta:                      # reaches top speed
                return distance / speed + ta
            return 2 * (distance * ta / speed).sqrt()       # triangle

        duration = max((trapezoid(_dec(d), _dec(v)) for d, v in zip(timing.distances, timing.top_speeds)),
                       default=Decimal(0))
        decel = min(ta, duration / 2)
        if timing.blend <= 0:
            blend = Decimal(0)
        elif timing.blend_is_radius:
            fraction = min(Decimal(1), _dec(timing.blend) / max(_dec(timing.blend_speed) * decel / 2,
                                                                _dec(Fraction(1e-9))))
            blend = fraction * decel
        else:
            blend = min(Decimal(1), _dec(timing.blend) / 100) * decel
        settle = _dec(timing.settle_ms) / 1000
        return (_nearest(duration * scale), _nearest(decel * scale), _nearest(blend * scale),
                _nearest(settle * scale))


# ---------------------------------------------------------------- random inputs

_floats = st.floats(min_value=0.0, max_value=400.0, allow_nan=False, allow_infinity=False)
_speeds = st.floats(min_value=0.01, max_value=300.0, allow_nan=False, allow_infinity=False)


@settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(distances=st.lists(_floats, min_size=1, max_size=6), speed=_speeds,
       accel_ms=st.integers(0, 3000), scale=st.sampled_from([1.0, 0.1, 0.01, 0.37, 2.5]),
       blend=st.floats(0.0, 150.0, allow_nan=False), radius=st.booleans(), settle=st.integers(0, 500))
def test_timing_model_matches_the_reference(distances, speed, accel_ms, scale, blend, radius, settle):
    timing = SegmentTiming(tuple(Fraction(d) for d in distances), tuple(Fraction(speed) * (i + 1) for i in range(len(distances))),
                           Fraction(accel_ms) / 1000, Fraction(scale), Fraction(blend), radius, Fraction(speed),
                           Fraction(settle))
    assert timing.times_ns() == reference_times_ns(timing)


def test_ties_round_to_even():
    # 1.5 ns and 2.5 ns of motion: exact halves
    half = SegmentTiming((Fraction(3, 2),), (Fraction(10**9),), Fraction(0), Fraction(1))
    assert half.times_ns()[0] == 2
    two_and_half = SegmentTiming((Fraction(5, 2),), (Fraction(10**9),), Fraction(0), Fraction(1))
    assert two_and_half.times_ns()[0] == 2


# ---------------------------------------------------------------- the golden PnP run


def test_every_segment_and_tag_of_the_golden_pnp_run_matches_the_reference(monkeypatch):
    from emulator.motion import MotionExecutor, Segment
    from stvm.trace import TraceSpec, run_trace
    planned = []
    original = MotionExecutor.enqueue

    def enqueue(self, item):   # what the robot queued (a script's dry run plans but never queues)
        if isinstance(item, Segment):
            planned.append(item)
        return original(self, item)

    monkeypatch.setattr(MotionExecutor, "enqueue", enqueue)
    run = run_trace(TraceSpec([ROOT / "st_src" / "PnP_Example.st"],
                              scenario=ROOT / "st_src" / "scenarios" / "golden_pnp_cycle.toml"))
    assert run.fault is None and len(planned) >= 12   # two cycles of six PTP segments (and a third begun)
    for seg in planned:
        assert (seg.duration_ns, seg.accel_ns, seg.blend_ns, seg.settle_ns) == reference_times_ns(seg.timing)
    tags = [f for f in run.trace.frames if f.direction == "tx" and ",01," in f.text() and "true" in f.text()]
    assert 12 <= len(tags) <= len(planned)
    # no blending, no pause: QueueTag N is reached when its segment's motion ends
    for seg, tag in zip(planned, tags):
        assert tag.t_ns == seg.start_ns + seg.duration_ns + seg.settle_ns


# ---------------------------------------------------------------- bit-identical arithmetic

PINNED = {   # computed once; detmath uses only exactly rounded operations, so these hold everywhere
    "sin(1)": (dm.sin(1.0), "0x1.aed548f090ceep-1"),
    "cos(2)": (dm.cos(2.0), "-0x1.aa22657537205p-2"),
    "sin(1e7)": (dm.sin(1e7), "0x1.aea414a8a3351p-2"),
    "atan2(1,2)": (dm.atan2(1.0, 2.0), "0x1.dac670561bb4fp-2"),
    "acos(0.3)": (dm.acos(0.3), "0x1.441f5ecbeef58p+0"),
    "asin(-0.7)": (dm.asin(-0.7), "-0x1.8d00e692afd96p-1"),
}


@pytest.mark.parametrize("name", sorted(PINNED))
def test_detmath_bit_patterns_are_pinned(name):
    value, expected = PINNED[name]
    assert value.hex() == expected


@settings(max_examples=500, deadline=None, derandomize=True)
@given(st.floats(-1e6, 1e6, allow_nan=False))
def test_detmath_trigonometry_is_within_a_few_ulp_of_libm(x):
    for mine, libm in ((dm.sin(x), math.sin(x)), (dm.cos(x), math.cos(x)), (dm.atan(x), math.atan(x))):
        assert abs(mine - libm) <= 8 * math.ulp(max(abs(libm), 1e-300)) + 1e-300


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.floats(-1.0, 1.0, allow_nan=False), st.floats(-100, 100, allow_nan=False))
def test_detmath_inverse_trigonometry_is_within_a_few_ulp_of_libm(c, y):
    assert abs(dm.acos(c) - math.acos(c)) <= 8 * math.ulp(math.acos(c)) + 1e-300
    assert abs(dm.asin(c) - math.asin(c)) <= 8 * math.ulp(max(abs(math.asin(c)), 1e-300)) + 1e-300
    assert abs(dm.atan2(y, c) - math.atan2(y, c)) <= 8 * math.ulp(max(abs(math.atan2(y, c)), 1e-300)) + 1e-300


def test_other_blas_kernels_and_simd_levels_write_the_same_golden(tmp_path):
    # The kernels numpy would pick on other CPUs (no FMA, SSE only): the trace is byte-identical
    out = tmp_path / "pnp.jsonl"
    env = dict(os.environ, OPENBLAS_CORETYPE="Prescott",
               NPY_DISABLE_CPU_FEATURES="AVX2 FMA3 AVX F16C SSE42 SSE41 POPCNT SSSE3")
    result = subprocess.run([sys.executable, "-m", "stvm", "trace", "st_src/PnP_Example.st", "--scenario",
                             "st_src/scenarios/golden_pnp_cycle.toml", "-o", str(out)],
                            cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert out.read_bytes() == (ROOT / "tests" / "golden" / "pnp_cycle.jsonl").read_bytes()


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.floats(-1e7, 1e7, allow_nan=False))
def test_detmath_sincos_is_sin_and_cos_to_the_bit(x):
    s, c = dm.sincos(x)
    assert (s.hex(), c.hex()) == (dm.sin(x).hex(), dm.cos(x).hex())


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.lists(st.floats(-170, 170, allow_nan=False), min_size=6, max_size=6),
       st.lists(st.floats(-60, 60, allow_nan=False), min_size=6, max_size=6),
       st.booleans())
def test_ik_on_lists_gives_the_bits_of_the_ik_on_arrays(seed, offset, with_tool):
    """`Kinematics._ik` (plain lists) against `_ik_arrays` (numpy, the reference): the same
    solution to the bit, or None for both, from targets near and far from the seed."""
    from emulator.motion import Kinematics, pose_to_matrix
    kin = Kinematics()
    target = kin.fk(np.array(seed) + np.array(offset))
    tool = pose_to_matrix([1.5, -2.0, 110.0, 0.0, 0.0, 30.0]) if with_tool else None
    fast = kin._ik(target, np.array(seed), tool, 100)
    reference = Kinematics()._ik_arrays(target, np.array(seed), tool, 100)
    assert (fast is None) == (reference is None)
    if fast is not None:
        assert fast.tobytes() == reference.tobytes()
