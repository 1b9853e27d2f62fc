"""Motion model (spec §8): kinematics, trapezoid timing, completion time through the link."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emulator.framing import encode
from emulator.motion import (Kinematics, matrix_to_pose, pose_to_matrix, trapezoid_duration_s,
                             trapezoid_fraction)
from emulator.settings import EmulatorSettings
from emulator.transport import InProcessLink

MS = 1_000_000


def test_home_pose() -> None:
    pose = matrix_to_pose(Kinematics().fk([0, 0, 90, 0, 90, 0]))
    assert np.allclose(pose, [417.5, -122.3, 360.9, 180, 0, 90], atol=1e-6) or \
        np.allclose(pose, [417.5, -122.3, 360.9, -180, 0, 90], atol=1e-6)


def test_ik_round_trip() -> None:
    kin = Kinematics()
    target = pose_to_matrix([400, -100, 350, 180, 0, 90])
    joints = kin.ik(target, [0, 0, 90, 0, 90, 0])
    assert joints is not None
    assert np.allclose(kin.fk(joints)[:3, 3], target[:3, 3], atol=0.02)
    assert kin.ik(pose_to_matrix([2000, 0, 0, 180, 0, 0]), [0, 0, 90, 0, 90, 0]) is None


@pytest.mark.parametrize(("distance", "speed", "accel", "expected"), [
    (100.0, 100.0, 0.2, 1.2),                          # trapezoid: D/v + ta
    (10.0, 100.0, 0.2, 2 * math.sqrt(10 * 0.2 / 100)),  # triangle
    (0.0, 100.0, 0.2, 0.0),
])
def test_trapezoid_duration(distance: float, speed: float, accel: float, expected: float) -> None:
    assert trapezoid_duration_s(distance, speed, accel) == pytest.approx(expected)


def test_trapezoid_fraction_is_monotonic_and_symmetric() -> None:
    values = [trapezoid_fraction(t / 100, 1.2, 0.2) for t in range(121)]
    assert values[0] == 0 and values[-1] == 1
    assert all(b >= a for a, b in zip(values, values[1:]))
    assert trapezoid_fraction(0.6, 1.2, 0.2) == pytest.approx(0.5)


def _tag_time(script: str, step_ns: int, settings: EmulatorSettings = EmulatorSettings(), latency_ns: int = 0) -> int:
    link = InProcessLink(settings, latency_ns=latency_ns)
    client = link.endpoint()
    client.connect()
    link.step(step_ns)
    while client.status != "connected":
        link.step(step_ns)
    assert client.send(encode("TMSCT", "1," + script)) > 0
    for _ in range(100_000):
        link.step(step_ns)
        data = client.recv(65536)
        if b"$TMSTA,10,01,01,true" in data:
            return link.now_ns
    raise AssertionError("tag never reached")


@pytest.mark.parametrize("step_ms", [1, 4, 10])
def test_joint_motion_completes_at_modelled_time(step_ms: int) -> None:
    # J6 moves 90 deg at 20 % of 225 deg/s = 45 deg/s with 200 ms acceleration:
    # 90/45 + 0.2 = 2.2 s (trapezoid, spec §8 model).
    step = step_ms * MS
    t = _tag_time('PTP("JPP",0,0,90,0,90,90,20,200,0,false)\r\nQueueTag(1)', step)
    start = step  # sent after the first step, zero latency
    assert abs((t - start) - 2_200 * MS) <= step


def test_line_motion_completes_at_modelled_time() -> None:
    # 100 mm along X at 100 mm/s ("CAP"), 100 ms acceleration: 100/100 + 0.1 = 1.1 s.
    step = 2 * MS
    script = 'Line("CAP",517.5,-122.3,360.9,180,0,90,100,100,0,false)\r\nQueueTag(1)'
    t = _tag_time(script, step)
    assert abs((t - step) - 1_100 * MS) <= step


def test_time_scale_and_latency() -> None:
    step = 1 * MS
    t = _tag_time('PTP("JPP",0,0,90,0,90,90,20,200,0,false)\r\nQueueTag(1)', step,
                  EmulatorSettings(time_scale=0.1), latency_ns=3 * MS)
    # connected after 2 latencies (send at 6 ms), request 3 ms, motion 220 ms, notification 3 ms.
    assert t == 6 * MS + 3 * MS + 220 * MS + 3 * MS


def test_blending_shortens_total_time() -> None:
    plain = 'PTP("JPP",0,0,90,0,90,45,20,200,0,false)\r\nPTP("JPP",0,0,90,0,90,90,20,200,0,false)\r\nQueueTag(1)'
    blended = plain.replace(",200,0,false)\r\nPTP", ",200,100,false)\r\nPTP", 1)
    t_plain = _tag_time(plain, MS)
    t_blend = _tag_time(blended, MS)
    assert t_plain - t_blend == pytest.approx(200 * MS, abs=2 * MS)  # full decel overlap at 100 %


def test_pose_advances_with_time() -> None:
    link = InProcessLink(latency_ns=0)
    client = link.endpoint()
    client.connect()
    link.step(MS)
    client.send(encode("TMSCT", '1,Line("CAP",517.5,-122.3,360.9,180,0,90,100,100,0,false)'))
    xs = []
    for _ in range(6):
        link.step(250 * MS)
        xs.append(link.robot.snapshot()["pose"][0])
    assert xs == sorted(xs) and xs[0] > 417.5 and xs[-1] == pytest.approx(517.5, abs=1e-3)


def test_circle_ends_on_the_end_point() -> None:
    link = InProcessLink(latency_ns=0)
    client = link.endpoint()
    client.connect()
    link.step(MS)
    client.send(encode("TMSCT", '1,Circle("CAP",467.5,-72.3,360.9,180,0,90,517.5,-122.3,360.9,180,0,90,'
                                 '100,100,0,0,false)\r\nQueueTag(1)'))
    link.step(10_000 * MS)
    assert b"01,01,true" in client.recv(65536)
    assert link.robot.snapshot()["pose"][:3] == pytest.approx([517.5, -122.3, 360.9], abs=0.05)
