"""CBT_MoveRelative (thesis Annex A3, st_src/CBT_MoveRelative.st) against the TM emulator.

Move_PTP() / Move_Line() with the offsets formatted by RealToFormatString(DecPlace 0, Sign TRUE)
(sysmac.md 8.13); expected frames computed from the protocol spec in thesis_harness.
"""

from __future__ import annotations

import pytest

from thesis_harness import (assert_done_once_after_drop, not_connected_states, move_script_tail, CHECK_LISTEN, CLOSE, LISTEN_OK, OUTPUTS, RESET, frame_checksum, make_bench_fixture,
                            pose_text, tag_notification, thesis_frame, tm_frame, tmsct_reply)

bench = make_bench_fixture()

OFFSET = {"X": -0.5, "Y": 0.0, "Z": -10.5, "RX": 0.0, "RY": 0.0, "RZ": 0.4}
# FB_step at the end of the Busy scans: 30 goes to 40, not 70 (README '+': A3 l.5554/5571 -> 5579)
NORMAL_STEPS = [20, 25, 30, 40, 50, 60, 70, 80, 90, 100, 110, 200]


def params(cmd_id=3, movement="PTP", fmt="TPP_Rel", offset=None, speed=100, accel=150, blend=None,
           precise=False, exit_node=False) -> dict:
    p = {"CommandID": cmd_id, "MovementCommand": movement, "DataFormat": fmt, "Speed": speed,
         "AccelTime": accel, "BlendingEnable": blend is not None, "BlendingValue": blend or 0,
         "PrecisePositioning": precise, "ExitNode": exit_node}
    p.update({f"TargetPosition.{k}": v for k, v in (offset or OFFSET).items()})
    return p


def expected_script(p: dict) -> str:
    """Annex A3 steps 30/40 from the spec: Move_PTP/Move_Line("fmt", 6 offsets as '+n'/'-n',
    speed, accel, blend or 0, precise) [+ CR LF QueueTag(id,0)] [+ CR LF ScriptExit()]."""
    move = "Move_PTP" if p["MovementCommand"] == "PTP" else "Move_Line"
    fmt = p["DataFormat"].split("_")[0]
    offs = pose_text(p[f"TargetPosition.{k}"] for k in ("X", "Y", "Z", "RX", "RY", "RZ"))
    blend = str(p["BlendingValue"]) if p["BlendingEnable"] else "0"
    script = f'{move}("{fmt}",{offs},{p["Speed"]},{p["AccelTime"]},{blend},{"true" if p["PrecisePositioning"] else "false"})'
    return script + move_script_tail(p)


def test_move_ptp_tool_normal_path(bench):
    b = bench("Rel")
    p = params()
    s0 = b.start_with(p)
    b.until_end()
    r = b.runner
    # -0.5 -> '-1', -10.5 -> '-11' (half away from zero), 0.4 -> '+0' (sysmac.md 8.13)
    expected = thesis_frame(3, 'Move_PTP("TPP",-1,+0,-11,+0,+0,+0,100,150,0,false)\r\nQueueTag(3,0)')
    assert expected == thesis_frame(3, expected_script(p))
    assert b.rx() == [CHECK_LISTEN, expected]
    assert b.tx() == [LISTEN_OK, tmsct_reply("3,OK"), tag_notification(3)]
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    assert r.busy_steps(s0) == NORMAL_STEPS
    wr_on = r.first(lambda s: s["WaitingReturn"], s0)
    wr_off = r.first(lambda s: not s["WaitingReturn"], wr_on.scan)
    done = r.first(lambda s: s["Done"], s0)
    assert done.scan - wr_off.scan == 3 and done["CmdID_Ack"] == 3
    assert r.since(s0)[1]["CmdID_Ack"] == 3
    # tool frame: TCP z axis points down at RX 180 -> -11 mm along tool Z = +11 mm in base Z
    pose = b.emulator.snapshot()["pose"]
    assert pose[2] == pytest.approx(360.9 + 11, abs=0.05)


@pytest.mark.parametrize("p", [
    pytest.param(params(4, "Line", "CAR_Rel", {"X": 0.0, "Y": 10.0, "Z": 0.0, "RX": 0.0, "RY": 0.0, "RZ": 0.0},
                        speed=200, blend=30), id="line-car-blending"),
    pytest.param(params(5, "PTP", "JPP_Rel", {"X": 5.0, "Y": 0.0, "Z": 0.0, "RX": 0.0, "RY": 0.0, "RZ": -5.0}),
                 id="ptp-jpp"),
    pytest.param(params(6, "Line", "TAP_Rel", {"X": 0.0, "Y": 0.0, "Z": -8.0, "RX": 0.0, "RY": 0.0, "RZ": 0.0},
                        speed=150, precise=True), id="line-tap-precise"),
    pytest.param(params(7, "PTP", "CPP_Rel", {"X": 0.0, "Y": 0.0, "Z": -10.0, "RX": 0.0, "RY": 0.0, "RZ": 0.0},
                        blend=10, exit_node=True), id="ptp-cpp-exitnode"),
])
def test_frames_and_done(bench, p):
    b = bench("Rel")
    s0 = b.start_with(p)
    b.until_end()
    assert b.rx() == [CHECK_LISTEN, thesis_frame(p["CommandID"], expected_script(p))]
    assert b.tx()[1] == tmsct_reply(f'{p["CommandID"]},OK')
    assert b.runner.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    assert b.runner.trace[-1]["CmdID_Ack"] == p["CommandID"]


def test_tag_of_another_command_accepted_8_4(bench):
    """sysmac.md 8.4: FIND(StringOfReceivedData, str_CommandID) finds the one-digit ID anywhere.
    CommandID 6; the robot reports tag 3 ('$TMSTA,10,01,03,true,*66': the 6 of the checksum)
    -> the FB takes it as its own completion and reports Done with CmdID_Ack 6."""
    p = params(6)
    frame = thesis_frame(6, expected_script(p))
    other = tag_notification(3)
    assert other == b"$TMSTA,10,01,03,true,*66\r\n"

    def robot(f, i):
        if f == CHECK_LISTEN:
            return [LISTEN_OK]
        return [tmsct_reply("6,OK"), 0.05, other]
    b = bench("Rel", robot="fake", responder=robot, extra=["StringOfReceivedData"])
    s0 = b.start_with(p)
    b.until_end(max_scans=5000)
    r = b.runner
    assert b.fake.frames == [CHECK_LISTEN, frame]
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    assert r.trace[-1]["CmdID_Ack"] == 6
    assert r.first(lambda s: s["FB_step"] == 110, s0)["StringOfReceivedData"].startswith(other)


def test_one_digit_checksum_cperr_stays_busy(bench):
    """sysmac.md 8.2: '*7' -> $CPERR,2,01 -> Busy in step 80 for ever, WaitingReturn TRUE;
    CBT_MoveAbsolute then fails with 16#11."""
    p = params(2, "PTP", "CPP_Rel", {"X": 5.0, "Y": 0.0, "Z": -6.0, "RX": 0.0, "RY": 0.0, "RZ": 0.0},
               blend=20, precise=True)
    frame = thesis_frame(2, expected_script(p))
    assert frame_checksum(frame) < 0x10 and frame.endswith(b",*7\r\n")
    b = bench("Rel")
    s0 = b.start_with(p)
    b.until(lambda s: s["FB_step"] == 80, "step 80")
    b.scans(300)
    r = b.runner
    assert b.rx() == [CHECK_LISTEN, frame]
    assert b.tx()[1] == tm_frame("CPERR", "01")
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0)]
    assert r.trace[-1]["FB_step"] == 80 and r.trace[-1]["WaitingReturn"]
    b.params({"CommandID": 2, "MovementCommand": "PTP", "DataFormat": "CPP_Abs", "TargetPosition.X": 417.0,
              "TargetPosition.Y": -122.0, "TargetPosition.Z": 350.0, "TargetPosition.RX": 180.0,
              "TargetPosition.RZ": 90.0, "Speed": 50, "AccelTime": 150}, inst="Abs")
    b.execute(True, inst="Abs")
    b.scans(5)
    assert b.vm.get("T.Abs.Error") and b.vm.get("T.Abs.ErrorID") == 0x11


def test_robot_error_reply_16_80(bench):
    b = bench("Rel", faults=["error"])
    p = params(4)
    s0 = b.start_with(p)
    b.until_end()
    r = b.runner
    assert b.rx() == [CHECK_LISTEN, thesis_frame(4, expected_script(p))]
    assert b.tx()[1] == tmsct_reply("4,ERROR;1")
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x80)]
    wr_off = r.first(lambda s: not s["WaitingReturn"], r.first(lambda s: s["WaitingReturn"], s0).scan)
    assert r.first(lambda s: s["Error"], s0).scan - wr_off.scan == 2
    assert b.get("ErrorDescrip") == b" Command rejected"


def test_connection_reset_mid_command_16_100(bench):
    """The robot answers OK, then resets the connection (RST) while the FB waits for the tag in
    step 100: SktTCPRcv fails -> 16#100 'TCP receive error'.  CBT_Connect does not notice a
    reset (sysmac.md 8.10: only _CLOSE_WAIT is checked): Connected stays TRUE."""
    p = params(5)

    def robot(f, i):
        if f == CHECK_LISTEN:
            return [LISTEN_OK]
        return [tmsct_reply("5,OK"), 0.05, RESET]
    b = bench("Rel", robot="fake", responder=robot)
    s0 = b.start_with(p)
    b.until_end(max_scans=5000)
    b.scans(1500)
    r = b.runner
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x100)]
    assert r.at(s0)["Connected"]
    err = r.first(lambda s: s["Error"], s0)
    assert r.at(err.scan - 3)["FB_step"] == 100
    assert b.get("ErrorDescrip") == b"TCP receive error"
    # WaitingReturn is left TRUE (step 100's error path does not release it) and the connection
    # still shows Connected: every later FB on this connection fails with 16#11
    assert all(s["Connected"] for s in r.since(s0))
    assert r.trace[-1]["WaitingReturn"]


def test_connection_closed_mid_command_16_99(bench):
    """The robot answers OK and closes (FIN) during the motion: CBT_Connect's status poll reports
    16#90 within 1 s; this FB then fails with 16#99 one scan after Connected falls."""
    def robot(f, i):
        if f == CHECK_LISTEN:
            return [LISTEN_OK]
        return [tmsct_reply("3,OK"), 0.02, CLOSE]
    b = bench("Rel", robot="fake", responder=robot)
    s0 = b.start_with(params(3))
    b.until(lambda s: s["Error"], "Error", max_scans=5000)
    r = b.runner
    down = r.first(lambda s: not s["Connected"], s0)
    err = r.first(lambda s: s["Error"], s0)
    assert err.scan - down.scan == 1 and err["ErrorID"] == 0x99
    assert b.vm.get("T.Conn.ErrorID") in (0, 0x90)   # CBT_Connect shows 16#90 two scans after Connected falls
    b.scans(2)
    assert b.vm.get("T.Conn.ErrorID") == 0x90


def test_execute_dropped_while_busy(bench):
    b = bench("Rel")
    p = params(8)
    s0 = b.start_with(p)
    b.scans(2)
    b.execute(False)
    b.until(lambda s: s["Done"], "Done")
    b.scans(2)
    assert_done_once_after_drop(b.runner, s0)
    assert b.runner.first(lambda s: s["Done"], s0)["CmdID_Ack"] == 8
    assert b.rx() == [CHECK_LISTEN, thesis_frame(8, expected_script(p))]


def test_not_connected_16_99(bench):
    b = bench("Rel", do_connect=False)
    s0 = b.start_with(params())
    b.scans(4)
    assert b.runner.output_states(s0) == not_connected_states(2)


@pytest.mark.parametrize("changes, error_id, descrip", [
    ({"Speed": 101}, 0x26, b"Speed range in PTP: 0~100 %"),
    ({"MovementCommand": "Line", "Speed": 4501}, 0x25, b"Speed range in Line: 0~4500 mm/s"),
    ({"AccelTime": 149}, 0x27, b"Acceleration Time range is: 150~9999 ms"),
    ({"CommandID": 10}, 0x28, b"Command ID range is: 2~9"),
    ({"DataFormat": "CAR_Rel"}, 0x30, b"DataFormat invalid for PTP command"),
    ({"MovementCommand": "Line", "DataFormat": "JPP_Rel"}, 0x31, b"DataFormat invalid for Line command"),
])
def test_parameter_range_errors(bench, changes, error_id, descrip):
    b = bench("Rel")
    p = params()
    p.update(changes)
    s0 = b.start_with(p)
    b.until(lambda s: s["Error"], "Error", max_scans=200)
    assert b.runner.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, error_id)]
    assert b.get("ErrorDescrip") == descrip
    assert b.rx() == [CHECK_LISTEN]
