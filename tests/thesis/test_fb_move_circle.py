"""CBT_MoveCircle (thesis Annex A4, st_src/CBT_MoveCircle.st) against the TM emulator.

Circle("fmt", arc point, end point, speed, accel, blend, arc angle, precise) - 18 flat arguments
(tm_protocol.md §7), points formatted with RealToFormatString(DecPlace 0, Sign TRUE).
"""

from __future__ import annotations

import pytest

from thesis_harness import (assert_done_once_after_drop, not_connected_states, move_script_tail, CHECK_LISTEN, LISTEN_OK, OUTPUTS, frame_checksum, make_bench_fixture, pose_text,
                            tag_notification, thesis_frame, tm_frame, tmsct_reply)

bench = make_bench_fixture()

# from the emulator's home pose (417.5, -122.3, 360.9): through (437.4, -102.6) to (457.5, -122.3)
ARC = {"X": 437.4, "Y": -102.6, "Z": 360.9, "RX": 180.0, "RY": 0.0, "RZ": 90.0}
END = {"X": 457.5, "Y": -122.3, "Z": 360.9, "RX": 180.0, "RY": 0.0, "RZ": 90.0}
NORMAL_STEPS = [20, 25, 30, 40, 50, 60, 70, 80, 90, 100, 110, 200]


def params(cmd_id=4, fmt="CPP_Circle", arc=None, end=None, speed=50, accel=150, blend=None, arc_angle=0,
           precise=False, exit_node=False) -> dict:
    p = {"CommandID": cmd_id, "DataFormat": fmt, "Speed": speed, "AccelTime": accel,
         "BlendingEnable": blend is not None, "BlendingValue": blend or 0, "ArcAngle": arc_angle,
         "PrecisePositioning": precise, "ExitNode": exit_node}
    p.update({f"ArcPoint.{k}": v for k, v in (arc or ARC).items()})
    p.update({f"EndPoint.{k}": v for k, v in (end or END).items()})
    return p


def expected_script(p: dict) -> str:
    """Annex A4 steps 30/40 from the spec."""
    keys = ("X", "Y", "Z", "RX", "RY", "RZ")
    fmt = p["DataFormat"].split("_")[0]
    blend = str(p["BlendingValue"]) if p["BlendingEnable"] else "0"
    script = (f'Circle("{fmt}",{pose_text(p["ArcPoint." + k] for k in keys)},'
              f'{pose_text(p["EndPoint." + k] for k in keys)},{p["Speed"]},{p["AccelTime"]},{blend},'
              f'{p["ArcAngle"]},{"true" if p["PrecisePositioning"] else "false"})')
    return script + move_script_tail(p)


def test_circle_normal_path(bench):
    b = bench("Circ")
    p = params()
    s0 = b.start_with(p)
    b.until_end()
    r = b.runner
    expected = thesis_frame(4, 'Circle("CPP",+437,-103,+361,+180,+0,+90,+458,-122,+361,+180,+0,+90,'
                               '50,150,0,0,false)\r\nQueueTag(4,0)')
    assert expected == thesis_frame(4, expected_script(p))
    assert b.rx() == [CHECK_LISTEN, expected]
    assert b.tx() == [LISTEN_OK, tmsct_reply("4,OK"), tag_notification(4)]
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    assert r.busy_steps(s0) == NORMAL_STEPS
    wr_off = r.first(lambda s: not s["WaitingReturn"], r.first(lambda s: s["WaitingReturn"], s0).scan)
    done = r.first(lambda s: s["Done"], s0)
    assert done.scan - wr_off.scan == 3 and done["CmdID_Ack"] == 4
    assert b.emulator.snapshot()["pose"][:3] == pytest.approx([458, -122, 361], abs=0.05)


@pytest.mark.parametrize("p", [
    pytest.param(params(5, "CAP_Circle", speed=100, arc_angle=90), id="cap-arcangle-90"),
    pytest.param(params(6, blend=40, precise=True), id="cpp-blending-precise"),
])
def test_frames_and_done(bench, p):
    b = bench("Circ")
    s0 = b.start_with(p)
    b.until_end()
    assert b.rx() == [CHECK_LISTEN, thesis_frame(p["CommandID"], expected_script(p))]
    assert b.tx()[1] == tmsct_reply(f'{p["CommandID"]},OK')
    assert b.runner.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    assert b.runner.trace[-1]["CmdID_Ack"] == p["CommandID"]


@pytest.mark.parametrize("fmt, speed", [("CAP_Circle", 101), ("CAP_Circle", 500), ("CPP_Circle", 101)])
def test_speed_above_100_is_16_26_whatever_the_unit(bench, fmt, speed):
    """README '+' (A4 l.6050/6061): step 25 checks both Speed > 4500 and Speed > 100 without
    looking at the data format, so a CAP (mm/s) circle above 100 mm/s fails with 16#26 'Speed
    range in PTP: 0~100 %' (original bug, kept)."""
    b = bench("Circ")
    s0 = b.start_with(params(fmt=fmt, speed=speed))
    b.until(lambda s: s["Error"], "Error", max_scans=200)
    assert b.runner.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x26)]
    assert b.get("ErrorDescrip") == b"Speed range in PTP: 0~100 %"
    assert b.rx() == [CHECK_LISTEN]


@pytest.mark.parametrize("changes, error_id", [
    ({"Speed": 4501}, 0x26),          # 16#25 is set, then overwritten by the > 100 check
    ({"AccelTime": 10000}, 0x27),
    ({"CommandID": 0}, 0x28),
])
def test_parameter_range_errors(bench, changes, error_id):
    b = bench("Circ")
    p = params()
    p.update(changes)
    s0 = b.start_with(p)
    b.until(lambda s: s["Error"], "Error", max_scans=200)
    assert b.runner.states(OUTPUTS, s0)[-1] == (False, False, True, error_id)
    assert b.rx() == [CHECK_LISTEN]


def test_one_digit_checksum_cperr_stays_busy(bench):
    p = params(7, arc={"X": 442.0, "Y": -98.0, "Z": 361.0, "RX": 180.0, "RY": 0.0, "RZ": 90.0},
               end={"X": 466.0, "Y": -122.0, "Z": 361.0, "RX": 180.0, "RY": 0.0, "RZ": 90.0}, precise=True)
    frame = thesis_frame(7, expected_script(p))
    assert frame_checksum(frame) < 0x10 and frame.endswith(b",*9\r\n")
    b = bench("Circ")
    s0 = b.start_with(p)
    b.until(lambda s: s["FB_step"] == 80, "step 80")
    b.scans(300)
    r = b.runner
    assert b.rx() == [CHECK_LISTEN, frame]
    assert b.tx()[1] == tm_frame("CPERR", "01")
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0)]
    assert r.trace[-1]["FB_step"] == 80 and r.trace[-1]["WaitingReturn"]


def test_robot_error_reply_16_80(bench):
    b = bench("Circ", faults=["error"])
    p = params(8)
    s0 = b.start_with(p)
    b.until_end()
    r = b.runner
    assert b.rx() == [CHECK_LISTEN, thesis_frame(8, expected_script(p))]
    assert b.tx()[1] == tmsct_reply("8,ERROR;1")
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x80)]
    assert not r.trace[-1]["WaitingReturn"]


def test_connection_lost_mid_motion(bench):
    b = bench("Circ", faults=["drop:30"])
    s0 = b.start_with(params(2))
    b.until(lambda s: s["Error"], "Error", max_scans=5000)
    r = b.runner
    down = r.first(lambda s: not s["Connected"], s0)
    err = r.first(lambda s: s["Error"], s0)
    assert err.scan - down.scan == 1 and err["ErrorID"] == 0x99
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x99)]


def test_execute_dropped_while_busy(bench):
    b = bench("Circ")
    p = params(3)
    s0 = b.start_with(p)
    b.scans(1)
    b.execute(False)
    b.until(lambda s: s["Done"], "Done")
    b.scans(2)
    assert_done_once_after_drop(b.runner, s0)
    assert b.rx() == [CHECK_LISTEN, thesis_frame(3, expected_script(p))]


def test_not_connected_16_99(bench):
    b = bench("Circ", do_connect=False)
    s0 = b.start_with(params())
    b.scans(4)
    assert b.runner.output_states(s0) == not_connected_states(2)


def test_reply_split_over_two_segments_8_5(bench):
    """sysmac.md 8.5: one receive per reply.  The robot's OK arrives in two TCP segments 50 ms
    apart; step 70 takes the first part, step 80 finds 'TMSCT' but neither 'OK' nor 'ERROR' and
    never receives again: Busy for ever (our own socket server does the split)."""
    p = params(5)
    ok = tmsct_reply("5,OK")

    def robot(f, i):
        return [LISTEN_OK] if f == CHECK_LISTEN else [ok[:9], 0.05, ok[9:]]
    b = bench("Circ", robot="fake", responder=robot, extra=["StringOfReceivedData"])
    s0 = b.start_with(p)
    b.until(lambda s: s["FB_step"] == 80, "step 80")
    b.scans(1500)
    r = b.runner
    assert b.fake.frames == [CHECK_LISTEN, thesis_frame(5, expected_script(p))]
    assert ok[:9] == b"$TMSCT,4,"
    assert r.first(lambda s: s["FB_step"] == 80, s0)["StringOfReceivedData"] == ok[:9]
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0)]
    assert all(s["FB_step"] == 80 and s["WaitingReturn"] for s in r.trace[-1000:])
