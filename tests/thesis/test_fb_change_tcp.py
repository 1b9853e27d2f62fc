"""CBT_ChangeTCP (thesis Annex A6, st_src/CBT_ChangeTCP.st) against the TM emulator.

ChangeTCP(offset[6], weight, Ixx, Iyy, Izz, mass centre[6]) - the 16-value form of
tm_protocol.md §7; every value through RealToFormatString(DecPlace 0, Sign TRUE), the UINT
Weight too (sysmac.md 8.13).
"""

from __future__ import annotations

import random

import pytest

from thesis_harness import (assert_done_once_after_drop, not_connected_states, CHECK_LISTEN, LISTEN_OK, OUTPUTS, RESET, frame_checksum, make_bench_fixture, pose_text,
                            rtfs0, thesis_frame, tm_frame, tmsct_reply)

bench = make_bench_fixture()

KEYS6 = ("X", "Y", "Z", "RX", "RY", "RZ")
NORMAL_STEPS = [20, 25, 30, 40, 50, 60, 70, 80, 90]


def params(cmd_id=2, offset=(0.0, 0.0, 150.5, 0.0, 0.0, 90.0), weight=2, inertia=(0.5, 1.49, 0.0),
           mass_center=(0.0, 0.0, -80.0, 0.0, 0.0, 0.0), exit_node=False) -> dict:
    p = {"CommandID": cmd_id, "Weight": weight, "ExitNode": exit_node}
    p.update({f"TCPOffset.{k}": v for k, v in zip(KEYS6, offset)})
    p.update({f"MomentOfInertia.{k}": v for k, v in zip(("Ixx", "Iyy", "Izz"), inertia)})
    p.update({f"MassCenter.{k}": v for k, v in zip(KEYS6, mass_center)})
    return p


def expected_script(p: dict) -> str:
    values = ([p["TCPOffset." + k] for k in KEYS6] + [p["Weight"]]
              + [p["MomentOfInertia." + k] for k in ("Ixx", "Iyy", "Izz")] + [p["MassCenter." + k] for k in KEYS6])
    script = f"ChangeTCP({pose_text(values)})"
    if p["ExitNode"]:
        script += "\r\nScriptExit()"
    return script


def test_change_tcp_normal_path(bench):
    b = bench("Tcp")
    p = params()
    s0 = b.start_with(p)
    b.until_end()
    r = b.runner
    # 150.5 -> +151, Weight UINT 2 -> '+2', inertia 0.5 -> +1, 1.49 -> +1 (sysmac.md 8.13)
    expected = thesis_frame(2, "ChangeTCP(+0,+0,+151,+0,+0,+90,+2,+1,+1,+0,+0,+0,-80,+0,+0,+0)")
    assert expected == thesis_frame(2, expected_script(p))
    assert rtfs0(2) == "+2"
    assert b.rx() == [CHECK_LISTEN, expected]
    assert b.tx() == [LISTEN_OK, tmsct_reply("2,OK")]
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    steps = []
    for s in r.since(s0):
        if s["Busy"] and (not steps or steps[-1] != s["FB_step"]):
            steps.append(s["FB_step"])
    assert steps == NORMAL_STEPS
    wr_off = r.first(lambda s: not s["WaitingReturn"], r.first(lambda s: s["WaitingReturn"], s0).scan)
    assert r.first(lambda s: s["Done"], s0).scan - wr_off.scan == 3
    assert b.emulator.snapshot()["tcp"] != "NOTOOL"


def test_exit_node_frame(bench):
    b = bench("Tcp")
    p = params(3, exit_node=True)
    s0 = b.start_with(p)
    b.until_end()
    assert b.rx() == [CHECK_LISTEN, thesis_frame(3, expected_script(p))]
    assert b.runner.states(OUTPUTS, s0)[-1] == (False, True, False, 0)


def test_checksum_never_one_digit():
    """As for ChangeBase: 16 signed values, the XOR's high nibble only depends on the parity of the
    digit count and is never 0 - no one-digit checksum (sysmac.md 8.2) for this FB."""
    rnd = random.Random(6)
    for _ in range(3000):
        p = params(rnd.randrange(0, 200), [rnd.uniform(-500, 500) for _ in KEYS6], rnd.randrange(0, 15),
                   [rnd.uniform(0, 100) for _ in range(3)], [rnd.uniform(-200, 200) for _ in KEYS6],
                   rnd.random() < 0.5)
        assert frame_checksum(thesis_frame(p["CommandID"], expected_script(p))) >= 0x10


@pytest.mark.parametrize("weight", [15, 100, 65535])
def test_weight_out_of_range_16_25(bench, weight):
    b = bench("Tcp")
    s0 = b.start_with(params(weight=weight))
    b.until(lambda s: s["Error"], "Error", max_scans=200)
    seq = b.runner.states(OUTPUTS, s0)
    assert seq == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x25)]
    assert b.get("ErrorDescrip") == b"Weight range: 0~14 kg"
    assert b.rx() == [CHECK_LISTEN]


def test_robot_error_reply_16_80(bench):
    b = bench("Tcp", faults=["error"])
    s0 = b.start_with(params(4))
    b.until_end()
    assert b.tx()[1] == tmsct_reply("4,ERROR;1")
    assert b.runner.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x80)]
    assert not b.runner.trace[-1]["WaitingReturn"]


def test_connection_reset_before_reply_16_70(bench):
    """The robot resets the connection instead of answering: SktTCPRcv (step 70) fails ->
    16#70 'TCP receive error'; WaitingReturn stays TRUE (not released on that path) and
    Connected stays TRUE (sysmac.md 8.10: a reset is _CLOSED, only _CLOSE_WAIT is checked)."""
    def robot(f, i):
        return [LISTEN_OK] if f == CHECK_LISTEN else [RESET]
    b = bench("Tcp", robot="fake", responder=robot)
    s0 = b.start_with(params(5))
    b.until_end(max_scans=5000)
    b.scans(1200)
    r = b.runner
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x70)]
    assert b.get("ErrorDescrip") == b"TCP receive error"
    assert r.trace[-1]["WaitingReturn"] and r.trace[-1]["Connected"]


def test_execute_dropped_while_busy(bench):
    b = bench("Tcp")
    s0 = b.start_with(params(6))
    b.scans(1)
    b.execute(False)
    b.until(lambda s: s["Done"], "Done")
    b.scans(2)
    assert_done_once_after_drop(b.runner, s0)


def test_not_connected_16_99(bench):
    b = bench("Tcp", do_connect=False)
    s0 = b.start_with(params())
    b.scans(4)
    assert b.runner.output_states(s0) == not_connected_states(2)


def test_cperr_reply_stays_busy(bench):
    """A CPERR reply has neither 'OK' nor 'ERROR': step 80 waits for ever, WaitingReturn TRUE."""
    def robot(f, i):
        return [LISTEN_OK] if f == CHECK_LISTEN else [tm_frame("CPERR", "F1")]
    b = bench("Tcp", robot="fake", responder=robot, extra=["StringOfReceivedData"])
    s0 = b.start_with(params(7))
    b.until(lambda s: s["FB_step"] == 80, "step 80")
    b.scans(600)
    r = b.runner
    assert b.fake.frames == [CHECK_LISTEN, thesis_frame(7, expected_script(params(7)))]
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0)]
    assert all(s["FB_step"] == 80 and s["WaitingReturn"] for s in r.trace[-500:])
    assert r.trace[-1]["StringOfReceivedData"] == b"$CPERR,2,F1,*3F\r\n"
