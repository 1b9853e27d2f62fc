"""CBT_ChangeBase (thesis Annex A5, st_src/CBT_ChangeBase.st) against the TM emulator.

ChangeBase(X,Y,Z,RX,RY,RZ) with RealToFormatString(DecPlace 0, Sign TRUE) values; no QueueTag:
Done follows the robot's 'OK' (any 'OK', README '+').
"""

from __future__ import annotations

import random

import pytest

import emulator
from thesis_harness import (assert_done_once_after_drop, not_connected_states, CHECK_LISTEN, CLOSE, LISTEN_OK, OUTPUTS, frame_checksum, make_bench_fixture,
                            pose_text, thesis_frame, tm_frame, tmsct_reply)

bench = make_bench_fixture()

KEYS6 = ("X", "Y", "Z", "RX", "RY", "RZ")
# FB_step at the end of the Busy scans
NORMAL_STEPS = [20, 30, 40, 50, 60, 70, 80, 90]


def params(cmd_id=2, values=(10.4, -20.5, 0.0, 0.0, 0.0, 45.0), exit_node=False) -> dict:
    p = {"CommandID": cmd_id, "ExitNode": exit_node}
    p.update({f"Transformation.{k}": v for k, v in zip(KEYS6, values)})
    return p


def expected_script(p: dict) -> str:
    script = f'ChangeBase({pose_text(p["Transformation." + k] for k in KEYS6)})'
    if p["ExitNode"]:
        script += "\r\nScriptExit()"
    return script


def test_change_base_normal_path(bench):
    b = bench("Base")
    p = params()
    s0 = b.start_with(p)
    b.until_end()
    b.scans(2)
    r = b.runner
    expected = thesis_frame(2, "ChangeBase(+10,-21,+0,+0,+0,+45)")     # 10.4 -> +10, -20.5 -> -21
    assert expected == thesis_frame(2, expected_script(p))
    assert b.rx() == [CHECK_LISTEN, expected]
    assert b.tx() == [LISTEN_OK, tmsct_reply("2,OK")]
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    assert r.busy_steps(s0) == NORMAL_STEPS
    wr_on = r.first(lambda s: s["WaitingReturn"], s0)
    wr_off = r.first(lambda s: not s["WaitingReturn"], wr_on.scan)
    assert wr_on["FB_step"] == 70 and wr_off["FB_step"] == 90
    assert r.first(lambda s: s["Done"], s0).scan - wr_off.scan == 3
    snap = b.emulator.snapshot()
    assert snap["base"] != "RobotBase"


@pytest.mark.parametrize("p", [
    pytest.param(params(12, (0.0, 0.0, 100.0, 0.0, 0.0, -90.5)), id="id-12-no-range-check"),
    pytest.param(params(3, (0.0, 0.0, 0.0, 0.0, 0.0, 0.0), exit_node=True), id="exitnode"),
])
def test_frames_and_done(bench, p):
    """ChangeBase has no CommandID range check (unlike the move FBs): ID 12 is sent as is."""
    b = bench("Base")
    s0 = b.start_with(p)
    b.until_end()
    assert b.rx() == [CHECK_LISTEN, thesis_frame(p["CommandID"], expected_script(p))]
    assert b.tx()[1] == tmsct_reply(f'{p["CommandID"]},OK')
    assert b.runner.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]


def test_checksum_never_one_digit():
    """No ChangeBase frame can carry a one-digit checksum: the high nibble of the XOR depends only
    on the parity of the number of digits (signs, commas and letters are fixed), and neither
    parity gives 0 - so the CPERR-by-checksum path (sysmac.md 8.2) does not exist for this FB.
    Checked on 3000 random parameter sets, with and without ScriptExit()."""
    rnd = random.Random(5)
    for _ in range(3000):
        p = params(rnd.randrange(0, 200), [rnd.uniform(-2000, 2000) for _ in KEYS6], rnd.random() < 0.5)
        assert frame_checksum(thesis_frame(p["CommandID"], expected_script(p))) >= 0x10


def test_any_ok_accepted(bench):
    """README '+' (A5 l.6740): step 80 accepts any reply containing 'OK' - here the OK of
    another command ID."""
    def robot(f, i):
        return [LISTEN_OK] if f == CHECK_LISTEN else [tmsct_reply("9,OK")]
    b = bench("Base", robot="fake", responder=robot)
    s0 = b.start_with(params(2))
    b.until_end(max_scans=3000)
    assert b.runner.states(OUTPUTS, s0)[-1] == (False, True, False, 0)
    assert b.fake.frames[1] == thesis_frame(2, expected_script(params(2)))


def test_robot_error_reply_16_80(bench):
    b = bench("Base", faults=["error"])
    s0 = b.start_with(params(4))
    b.until_end()
    r = b.runner
    assert b.tx()[1] == tmsct_reply("4,ERROR;1")
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x80)]
    wr_off = r.first(lambda s: not s["WaitingReturn"], r.first(lambda s: s["WaitingReturn"], s0).scan)
    assert r.first(lambda s: s["Error"], s0).scan - wr_off.scan == 2
    assert b.get("ErrorDescrip") == b" Command rejected"


def test_cperr_outside_listen_node_stays_busy(bench):
    """CPERR reply: a first ChangeBase with ExitNode leaves the Listen node (the emulator's flow
    then stays outside, after_exit=stay); the next ChangeBase gets $CPERR,2,F1 - no 'OK', no
    'ERROR' - and the FB stays Busy in step 80 with WaitingReturn TRUE (CBT_Connect does not
    notice: the socket is fine)."""
    b = bench("Base", settings=emulator.EmulatorSettings(after_exit="stay"))
    b.start_with(params(2, exit_node=True))
    b.until_end()
    assert b.runner.trace[-1]["Done"]
    b.execute(False)
    b.scans(3)
    p = params(3)
    s1 = b.start_with(p)
    b.until(lambda s: s["FB_step"] == 80, "step 80")
    b.scans(500)
    r = b.runner
    assert b.rx()[2] == thesis_frame(3, expected_script(p))
    assert b.tx()[-1] == tm_frame("CPERR", "F1") == b"$CPERR,2,F1,*3F\r\n"
    assert r.states(OUTPUTS, s1) == [(False, False, False, 0), (True, False, False, 0)]
    assert all(s["FB_step"] == 80 and s["WaitingReturn"] and s["Connected"] for s in r.trace[-400:])


def test_connection_lost_before_reply_16_99(bench):
    """The robot closes (FIN) instead of answering: SktTCPRcv completes with 0 bytes, step 80
    finds neither OK nor ERROR and waits; CBT_Connect's poll reports 16#90, then this FB 16#99."""
    def robot(f, i):
        return [LISTEN_OK] if f == CHECK_LISTEN else [CLOSE]
    b = bench("Base", robot="fake", responder=robot)
    s0 = b.start_with(params(5))
    b.until(lambda s: s["Error"], "Error", max_scans=5000)
    r = b.runner
    assert r.first(lambda s: s["Error"], s0).scan - r.first(lambda s: not s["Connected"], s0).scan == 1
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x99)]


def test_execute_dropped_while_busy(bench):
    b = bench("Base")
    s0 = b.start_with(params(6))
    b.scans(1)
    b.execute(False)
    b.until(lambda s: s["Done"], "Done")
    b.scans(2)
    assert_done_once_after_drop(b.runner, s0)


def test_not_connected_16_99(bench):
    b = bench("Base", do_connect=False)
    s0 = b.start_with(params())
    b.scans(4)
    assert b.runner.output_states(s0) == not_connected_states(2)


def test_other_fb_under_execution_16_11(bench):
    """A move waiting for its tag holds CBT.WaitingReturn: ChangeBase fails with 16#11."""
    b = bench("Base")
    b.params({"CommandID": 2, "MovementCommand": "PTP", "DataFormat": "CPP_Abs", "TargetPosition.X": 417.0,
              "TargetPosition.Y": -122.0, "TargetPosition.Z": 300.0, "TargetPosition.RX": 180.0,
              "TargetPosition.RZ": 90.0, "Speed": 20, "AccelTime": 150}, inst="Abs")
    b.execute(True, inst="Abs")
    b.until(lambda s: s["WaitingReturn"], "WaitingReturn")
    s0 = b.start_with(params(3))
    b.scans(5)
    seq = [tuple(s[k] for k in OUTPUTS) for s in b.runner.since(s0)]
    assert seq == [(False, False, False, 0), (True, False, False, 0), (True, False, False, 0),
                   (False, False, True, 0x11), (False, False, True, 0x11)]
    assert b.get("ErrorDescrip") == b"Other FB is under execution"
    assert len(b.wait_rx(2)) == 2


@pytest.mark.parametrize("values, text", [
    ((2.4999999, -2.4999999, 0.49999997, 89.99999, -1e-30, 1e-30),
     "+3,-3,+0,+90,-0,+0"),      # float32: 2.4999999 is 2.5 -> half away -> 3; -1e-30 -> '-0'
    ((12.5, -12.5, 0.5, -0.5, 1.5, 255.5), "+13,-13,+1,-1,+2,+256"),
    ((16777217.0, -123456789.0, 1000.4999, 0.0, 359.5, -359.5), "+16777216,-123456792,+1000,+0,+360,-360"),
])
def test_realtoformatstring_values_in_frame(bench, values, text):
    """sysmac.md §6/8.13 RealToFormatString(DecPlace 0, Sign TRUE) on the exact float32 value,
    half away from zero, '-0' for negatives that round to 0 - in the bytes on the wire."""
    b = bench("Base")
    p = params(2, values)
    s0 = b.start_with(p)
    b.until_end()
    assert pose_text(values) == text
    assert b.rx()[1] == thesis_frame(2, f"ChangeBase({text})")
    assert b.runner.states(OUTPUTS, s0)[-1] in ((False, True, False, 0), (False, False, True, 0x80))
