"""KUKA A/B/C -> TM RX/RY/RZ, computed in ST (st_src/kuka/KRC_Convert.st) on the VM, proved with
rotation matrices: for random angles (hypothesis) the TM angles the ST code returns give, in the TM
convention, the rotation matrix of the KUKA angles in the KUKA convention.

KUKA (seed E6POS: A about Z, B about Y, C about X): R = Rz(A) Ry(B) Rx(C).
TM: R = Rz(RZ) Ry(RY) Rx(RX) -- checked here against the emulator's own euler_to_matrix, the
convention the robot model moves with."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from emulator.motion import euler_to_matrix
from kuka_harness import kuka_project

TOLERANCE = 2e-5        # REAL (binary32) angles: ~1e-5 deg of rounding, far below this in the matrix


def rx(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def kuka_matrix(a, b, c):
    return rz(a) @ ry(b) @ rx(c)


def tm_matrix(rx_deg, ry_deg, rz_deg):
    return rz(rz_deg) @ ry(ry_deg) @ rx(rx_deg)


@pytest.fixture(scope="module")
def vm():
    machine = kuka_project().start(scan="1ms")
    yield machine
    machine.close()


def st_to_tm(vm, a, b, c):
    vm.set("K.InA", a)
    vm.set("K.InB", b)
    vm.set("K.InC", c)
    vm.scan()
    return vm.get("K.OutTM.RX"), vm.get("K.OutTM.RY"), vm.get("K.OutTM.RZ")


def st_to_kuka(vm, rx_deg, ry_deg, rz_deg):
    vm.set("K.InTM.RX", rx_deg)
    vm.set("K.InTM.RY", ry_deg)
    vm.set("K.InTM.RZ", rz_deg)
    vm.scan()
    return vm.get("K.OutE6.A"), vm.get("K.OutE6.B"), vm.get("K.OutE6.C")


def f32(value: float) -> float:
    return float(np.float32(value))


def test_our_tm_convention_is_the_emulators():
    rng = np.random.default_rng(7)
    for _ in range(200):
        angles = rng.uniform(-180, 180, 3)
        assert np.allclose(euler_to_matrix(*angles), tm_matrix(*angles), atol=1e-12)


ANGLE = st.floats(-180.0, 180.0, allow_nan=False, width=32)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a=ANGLE, b=ANGLE, c=ANGLE)
def test_kuka_to_tm_keeps_the_rotation(vm, a, b, c):
    out = st_to_tm(vm, a, b, c)
    assert np.allclose(tm_matrix(*out), kuka_matrix(a, b, c), atol=TOLERANCE)
    assert all(-180.0 <= v <= 180.0 for v in out)              # normalised (-180 only by REAL rounding)
    assert -90.0 - 1e-4 <= out[1] <= 90.0 + 1e-4                # RY from asin


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(a=st.floats(-720.0, 720.0, allow_nan=False, width=32), b=st.floats(-720.0, 720.0, allow_nan=False, width=32),
       c=st.floats(-720.0, 720.0, allow_nan=False, width=32))
def test_angles_outside_the_kuka_range_give_the_same_orientation(vm, a, b, c):
    assert np.allclose(tm_matrix(*st_to_tm(vm, a, b, c)), kuka_matrix(a, b, c), atol=TOLERANCE)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rx_deg=ANGLE, ry_deg=st.floats(-89.0, 89.0, width=32), rz_deg=ANGLE)
def test_tm_to_kuka_round_trip(vm, rx_deg, ry_deg, rz_deg):
    a, b, c = st_to_kuka(vm, rx_deg, ry_deg, rz_deg)
    assert np.allclose(kuka_matrix(a, b, c), tm_matrix(rx_deg, ry_deg, rz_deg), atol=TOLERANCE)
    back = st_to_tm(vm, a, b, c)
    assert np.allclose(tm_matrix(*back), tm_matrix(rx_deg, ry_deg, rz_deg), atol=TOLERANCE)


@pytest.mark.parametrize(("a", "b", "c"), [
    (0.0, 0.0, 0.0), (90.0, 0.0, 180.0), (-180.0, 0.0, 180.0), (180.0, 0.0, -180.0),
    (30.0, 90.0, 10.0), (30.0, -90.0, 10.0),               # gimbal lock: angles differ, orientation not
    (45.0, 89.99, -60.0), (0.0, 0.0, 270.0), (-90.0, 45.0, 45.0)])
def test_special_angles(vm, a, b, c):
    out = st_to_tm(vm, a, b, c)
    assert np.allclose(tm_matrix(*out), kuka_matrix(a, b, c), atol=TOLERANCE)


def test_ordinary_angles_map_component_wise(vm):
    """Away from B = +-90 both are the same ZYX product: RX = C, RY = B, RZ = A."""
    assert st_to_tm(vm, 12.5, -33.25, 170.0) == pytest.approx((170.0, -33.25, 12.5), abs=1e-4)
