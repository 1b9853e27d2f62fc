"""CBT_MoveAbsolute (thesis Annex A2, st_src/CBT_MoveAbsolute.st) against the TM emulator.

Expected frames are computed here from the TM protocol spec (thesis_harness.thesis_frame /
rtfs0), not taken from stvm or the emulator, and compared byte for byte with what the emulator
logged.  Original bugs that shape the frames or the sequence are asserted as the thesis code
behaves (st_src/README.md "Original bugs kept on purpose", sysmac.md 8.x).
"""

from __future__ import annotations

import pytest

import emulator
from thesis_harness import (assert_done_once_after_drop, not_connected_states, move_script_tail, CHECK_LISTEN, LISTEN_OK, OUTPUTS, frame_checksum, make_bench_fixture, pose_text,
                            tag_notification, thesis_frame, tm_frame, tmsct_reply)

bench = make_bench_fixture()

# a 10 mm move below the emulator's home pose (417.5, -122.3, 360.9, 180, 0, 90)
TARGET = {"X": 417.4, "Y": -122.6, "Z": 350.5, "RX": 180.0, "RY": -0.3, "RZ": 90.0}
# FB_step at the end of the Busy scans (step 10 runs in the first Busy scan and sets 20)
NORMAL_STEPS = [20, 25, 30, 35, 40, 50, 60, 70, 80, 90, 100, 110, 200]


def params(cmd_id=2, movement="PTP", fmt="CPP_Abs", target=None, speed=100, accel=150, blend=None,
           precise=False, pose=None, exit_node=False) -> dict:
    target = target or TARGET
    p = {"CommandID": cmd_id, "MovementCommand": movement, "DataFormat": fmt, "Speed": speed,
         "AccelTime": accel, "BlendingEnable": blend is not None, "BlendingValue": blend or 0,
         "PrecisePositioning": precise, "RobotPoseEnable": pose is not None, "ExitNode": exit_node}
    p.update({f"TargetPosition.{k}": v for k, v in target.items()})
    if pose is not None:
        p.update({"RobotPose.Pose1": pose[0], "RobotPose.Pose2": pose[1], "RobotPose.Pose3": pose[2]})
    return p


def expected_script(p: dict) -> str:
    """Annex A2 steps 35/40 rendered from the spec: RealToFormatString DecPlace 0 with '+'
    (sysmac.md 8.13), UINT_TO_STRING, 'true'/'false', pose 'p1,p2,p3', QueueTag(id,0) unless
    blending, ScriptExit() on ExitNode, lines joined by CR LF."""
    fmt = p["DataFormat"].split("_")[0]
    target = pose_text(p[f"TargetPosition.{k}"] for k in ("X", "Y", "Z", "RX", "RY", "RZ"))
    blend = str(p["BlendingValue"]) if p["BlendingEnable"] else "0"
    args = f'{target},{p["Speed"]},{p["AccelTime"]},{blend},{"true" if p["PrecisePositioning"] else "false"}'
    if p["RobotPoseEnable"]:
        args += f',{p["RobotPose.Pose1"]},{p["RobotPose.Pose2"]},{p["RobotPose.Pose3"]}'
    script = f'{p["MovementCommand"]}("{fmt}",{args})'
    return script + move_script_tail(p)


def run_move(b, p: dict) -> int:
    b.params(p)
    return b.execute(True)


def step_sequence(runner, start: int) -> list[int]:
    out: list[int] = []
    for s in runner.since(start):
        if s["Busy"] and (not out or out[-1] != s["FB_step"]):
            out.append(s["FB_step"])
    return out


# ------------------------------------------------------------------------------- normal path


def test_ptp_normal_path_per_scan_and_frame(bench):
    b = bench("Abs", extra=["StringOfReceivedData"])
    p = params()
    s0 = run_move(b, p)
    b.until_end()
    b.scans(3)
    r = b.runner
    trace = r.since(s0)
    # --- frame: byte for byte against the spec computation, incl. sysmac.md 8.13 rounding:
    # 417.4 -> '+417', -122.6 -> '-123', 350.5 -> '+351' (half away from zero), -0.3 -> '-0'
    expected = thesis_frame(2, 'PTP("CPP",+417,-123,+351,+180,-0,+90,100,150,0,false)\r\nQueueTag(2,0)')
    assert expected == thesis_frame(2, expected_script(p))
    assert b.rx() == [CHECK_LISTEN, expected]
    assert b.tx() == [LISTEN_OK, tmsct_reply("2,OK"), tag_notification(2)]
    # --- per scan
    assert (trace[0]["Busy"], trace[0]["Done"], trace[0]["Error"]) == (False, False, False)  # R_TRIG scan: Reset
    assert trace[1]["Busy"] and trace[1]["CmdID_Ack"] == 2      # step 10 loads Parameters.CommandID (README '+')
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    # the algorithm's steps in order; 35 goes to 40, not 70 (README '+': step overwritten later)
    assert step_sequence(r, s0) == NORMAL_STEPS
    # WaitingReturn: TRUE from the send until the tag notification; Done exactly 3 scans after it
    # falls (step 110 -> 200 -> ToDone_Sts -> state 5, sysmac.md 8.9)
    wr_on = r.first(lambda s: s["WaitingReturn"], s0)
    wr_off = r.first(lambda s: not s["WaitingReturn"], wr_on.scan)
    done = r.first(lambda s: s["Done"], s0)
    assert wr_on["FB_step"] == 70 and wr_off["FB_step"] == 200
    assert done.scan - wr_off.scan == 3
    assert not done["Busy"] and done["CmdID_Ack"] == 2 and done["ErrorID"] == 0
    # Done held while Execute stays TRUE; state 5 sees Execute FALSE (Done still TRUE in that
    # scan, -> state 6), Done FALSE from the next scan
    assert all(s["Done"] for s in r.since(done.scan))
    b.execute(False)
    b.scans(2)
    assert [(s["Busy"], s["Done"]) for s in r.trace[-2:]] == [(False, True), (False, False)]
    # the robot went to the whole-millimetre target
    pose = b.emulator.snapshot()["pose"]
    assert pose == pytest.approx([417, -123, 351, 180, 0, 90], abs=0.01)


@pytest.mark.parametrize("p, done_from_step", [
    pytest.param(params(3, "PTP", "JPP_Abs", {"X": 5.0, "Y": 0.0, "Z": 90.0, "RX": 0.0, "RY": 90.0, "RZ": 0.0}),
                 110, id="ptp-jpp"),
    pytest.param(params(4, "PTP", "CPP_Abs", precise=True, pose=(0, 2, 4)), 110, id="ptp-pose-precise"),
    pytest.param(params(5, "Line", "CAP_Abs", speed=200, blend=50), 80, id="line-cap-blending"),
    pytest.param(params(6, "Line", "CPR_Abs", speed=100, blend=20, exit_node=True), 80, id="line-exitnode"),
])
def test_frames_and_done(bench, p, done_from_step):
    """Frame variants (data formats, pose, precise positioning, blending without QueueTag,
    ScriptExit()); with blending Done follows the OK (step 80 -> 200), else the tag (110 -> 200)."""
    b = bench("Abs")
    s0 = run_move(b, p)
    b.until_end()
    r = b.runner
    assert b.rx() == [CHECK_LISTEN, thesis_frame(p["CommandID"], expected_script(p))]
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    done = r.trace[-1]
    assert done["CmdID_Ack"] == p["CommandID"]
    wr_off = r.first(lambda s: not s["WaitingReturn"], r.first(lambda s: s["WaitingReturn"], s0).scan)
    assert r.at(wr_off.scan - 1)["FB_step"] == done_from_step
    assert done.scan - wr_off.scan == 3
    tx = b.tx()
    assert tx[1] == tmsct_reply(f'{p["CommandID"]},OK')
    if not p["BlendingEnable"]:
        assert tx[2] == tag_notification(p["CommandID"])


# ------------------------------------------------------------------------------- one-digit checksum

ONE_DIGIT = params(2, "PTP", "CPP_Abs", {"X": 417.0, "Y": -122.0, "Z": 345.0, "RX": 180.0, "RY": 0.0, "RZ": 90.0},
                   speed=50, blend=50)


def test_one_digit_checksum_cperr_stays_busy_then_16_11(bench):
    """sysmac.md 8.2 / ERRATA Q2: BYTE_TO_STRING gives '7' for 16#07; the robot answers
    $CPERR,2,01 (tm_protocol.md §11 #9 default); step 80 only looks for TMSTA/TMSCT, so the FB
    stays Busy with WaitingReturn TRUE, and the next FB fails with 16#11."""
    b = bench("Abs", extra=["StringOfReceivedData"])
    frame = thesis_frame(2, expected_script(ONE_DIGIT))
    assert frame_checksum(frame) < 0x10 and frame.endswith(b",*7\r\n")
    s0 = run_move(b, ONE_DIGIT)
    b.until(lambda s: s["FB_step"] == 80, "step 80")
    b.scans(500)
    r = b.runner
    assert b.rx() == [CHECK_LISTEN, frame]
    assert b.tx()[1] == b"$CPERR,2,01,*49\r\n"      # tm_protocol.md §6 vector
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0)]
    assert all(s["FB_step"] == 80 and s["WaitingReturn"] for s in r.trace[-400:])
    assert b.get("StringOfReceivedData") == b"$CPERR,2,01,*49\r\n"
    # CBT_MoveRelative now finds the robot occupied: 16#11 'Other FB is under execution'
    b.runner.watch.update({f"Rel{k}": f"T.Rel.{k}" for k in OUTPUTS})
    b.params({"CommandID": 3, "MovementCommand": "PTP", "DataFormat": "TPP_Rel", "TargetPosition.Z": 5.0,
              "Speed": 50, "AccelTime": 150}, inst="Rel")
    s1 = b.execute(True, inst="Rel")
    b.scans(6)
    assert r.states(tuple(f"Rel{k}" for k in OUTPUTS), s1) == [
        (False, False, False, 0), (True, False, False, 0), (False, False, True, 0x11)]
    assert [s["RelBusy"] for s in r.since(s1)][:4] == [False, True, True, False]
    assert b.vm.get("T.Rel.ErrorDescrip") == b"Other FB is under execution"
    assert len(b.rx()) == 2


def test_one_digit_checksum_accepted_by_lenient_robot(bench):
    """ERRATA Q2: whether a one-digit checksum works is the robot's decision; with the emulator's
    `accept_one_digit_checksum` the same frame is executed and the FB completes (blending: Done at OK)."""
    b = bench("Abs", settings=emulator.EmulatorSettings(accept_one_digit_checksum=True))
    s0 = run_move(b, ONE_DIGIT)
    b.until_end()
    assert b.rx()[1].endswith(b",*7\r\n")
    assert b.runner.states(OUTPUTS, s0)[-1] == (False, True, False, 0)
    assert b.runner.trace[-1]["CmdID_Ack"] == 2


# ------------------------------------------------------------------------------- robot says no


@pytest.mark.parametrize("how", ["unreachable", "fault_error"])
def test_robot_error_reply_16_80(bench, how):
    """`$TMSCT,..,<id>,ERROR;1` -> WaitingReturn FALSE and 16#80 ' Command rejected' in step 80;
    Error two scans later."""
    if how == "unreachable":
        b = bench("Abs")
        p = params(7, target={"X": 2000.0, "Y": 0.0, "Z": 300.0, "RX": 180.0, "RY": 0.0, "RZ": 90.0})
    else:
        b = bench("Abs", faults=["error"])
        p = params(7)
    s0 = run_move(b, p)
    b.until_end()
    b.scans(2)
    r = b.runner
    assert b.rx() == [CHECK_LISTEN, thesis_frame(7, expected_script(p))]
    assert b.tx()[1] == tmsct_reply("7,ERROR;1")
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x80)]
    wr_off = r.first(lambda s: not s["WaitingReturn"], r.first(lambda s: s["WaitingReturn"], s0).scan)
    assert wr_off["FB_step"] == 80
    assert r.first(lambda s: s["Error"], s0).scan - wr_off.scan == 2
    assert b.get("ErrorDescrip") == b" Command rejected"
    assert r.trace[-1]["CmdID_Ack"] == 7       # loaded in step 10 from Parameters (README '+')


def test_motion_failed_16_110(bench):
    """Tag notification 'false' (emulator fault tag_false) -> 16#110 ' Motion failed'."""
    b = bench("Abs", faults=["tag_false"])
    s0 = run_move(b, params(8))
    b.until_end()
    assert b.runner.states(OUTPUTS, s0)[-1] == (False, False, True, 0x110)
    assert b.get("ErrorDescrip") == b" Motion failed"
    assert b.tx()[-1] == tm_frame("TMSTA", "01,08,false")


# ------------------------------------------------------------------------------- connection


def test_connection_lost_mid_motion(bench):
    """Emulator fault drop:20 closes the socket 20 ms into the motion (FIN).  The FB, in step
    100, keeps 'receiving' 0 bytes (peer closed) and re-reads the stale OK (sysmac.md 8.3);
    CBT_Connect's 1 s status poll sees _CLOSE_WAIT -> 16#90, Connected FALSE; the move FB then
    raises 16#99 (Execute AND NOT Connected), Error one scan after Connected falls (the harness
    calls CBT_Connect first in the scan: ToError_Sts in that scan, state 3 next)."""
    b = bench("Abs", faults=["drop:20"], extra=["StringOfReceivedData"])
    s0 = run_move(b, params(2))
    b.until(lambda s: s["Error"], "Error", max_scans=5000)
    b.scans(3)
    r = b.runner
    down = r.first(lambda s: not s["Connected"], s0)
    err = r.first(lambda s: s["Error"], s0)
    assert err.scan - down.scan == 1
    assert err["ErrorID"] == 0x99 and b.get("ErrorDescrip") == b"Robot not connected"
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x99)]
    assert b.vm.get("T.Conn.ErrorID") == 0x90
    # while waiting, step 100/110 looped on the stale OK bytes (AryToString of 256, 8.3)
    stale = {s["StringOfReceivedData"] for s in r.since(s0) if s["FB_step"] == 110}
    assert stale == {tmsct_reply("2,OK")}


def test_not_connected_16_99(bench):
    """Execute without a connection: the check above the state diagram sets 16#99 every scan
    (README '+'); step 10's 16#10 is overwritten by it.  Exact scans: Reset, Busy, Error."""
    b = bench("Abs", do_connect=False)
    s0 = run_move(b, params(2))
    b.scans(5)
    assert b.runner.output_states(s0) == not_connected_states(3)
    assert b.get("ErrorDescrip") == b"Robot not connected"


# ------------------------------------------------------------------------------- Execute dropped


def test_execute_dropped_while_busy(bench):
    """Execute FALSE while Busy does not abort; a new rising edge while Busy is ignored (FB_status
    = 2); at the end Done shows for exactly one scan (state 5 -> 6 in the same scan)."""
    b = bench("Abs")
    p = params(9)
    s0 = run_move(b, p)
    b.scans(3)
    b.execute(False)
    b.scans(3)
    b.execute(True)          # re-trigger while Busy: ignored
    b.scans(2)
    b.execute(False)
    b.until(lambda s: s["Done"], "Done")
    b.scans(3)
    r = b.runner
    assert_done_once_after_drop(b.runner, s0)
    assert r.first(lambda s: s["Done"], s0)["CmdID_Ack"] == 9
    assert b.rx() == [CHECK_LISTEN, thesis_frame(9, expected_script(p))]


# ------------------------------------------------------------------------------- range checks


@pytest.mark.parametrize("changes, error_id, descrip", [
    ({"Speed": 101}, 0x26, b"Speed range in PTP: 0~100 %"),
    ({"MovementCommand": "Line", "DataFormat": "CPP_Abs", "Speed": 4501}, 0x25, b"Speed range in Line: 0~4500 mm/s"),
    ({"AccelTime": 149}, 0x27, b"Acceleration Time range is: 150~9999 ms"),
    ({"AccelTime": 10000}, 0x27, b"Acceleration Time range is: 150~9999 ms"),
    ({"CommandID": 1}, 0x28, b"Command ID range is: 2~9"),
    ({"CommandID": 10}, 0x28, b"Command ID range is: 2~9"),
    ({"MovementCommand": "Line", "RobotPoseEnable": True, "RobotPose.Pose2": 2, "RobotPose.Pose3": 4},
     0x29, b"Robot Pose must be disable for Line command"),
    ({"RobotPoseEnable": True, "RobotPose.Pose1": 2, "RobotPose.Pose2": 2, "RobotPose.Pose3": 4}, 0x30, b"Pose1 range is 0~1"),
    ({"RobotPoseEnable": True, "RobotPose.Pose2": 4, "RobotPose.Pose3": 4}, 0x31, b"Pose2 range is 2~3"),
    ({"RobotPoseEnable": True, "RobotPose.Pose2": 2, "RobotPose.Pose3": 6}, 0x32, b"Pose3 range is 4~5"),
    ({"DataFormat": "CAP_Abs"}, 0x35, b"DataFormat invalid for PTP command"),
    ({"MovementCommand": "Line", "DataFormat": "JPP_Abs"}, 0x36, b"DataFormat invalid for Line command"),
])
def test_parameter_range_errors(bench, changes, error_id, descrip):
    """Steps 25/30/35: ToError_Sts, yet the algorithm runs one more step while the state diagram
    catches up (sysmac.md 8.9) - no frame is sent; Error two scans after the checking step."""
    b = bench("Abs")
    p = params(2)
    p.update(changes)
    s0 = run_move(b, p)
    b.until(lambda s: s["Error"], "Error", max_scans=200)
    b.scans(3)
    r = b.runner
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, error_id)]
    assert b.get("ErrorDescrip") == descrip
    assert b.rx() == [CHECK_LISTEN]
    assert not any(s["WaitingReturn"] for s in r.trace)


# ------------------------------------------------------------------------------- receive bugs


def test_stale_receive_bytes_8_3(bench):
    """sysmac.md 8.3: AryToString(TCP_Rcv_Data[0], TCP_Rcv_Size) converts the 256 bytes
    requested, not RcvSize: a short reply is followed by the tail of an older, longer one (up to
    the first 16#00).  Second command on the same instance: its OK (19 bytes) + the end of the
    previous tag notification (26 bytes)."""
    b = bench("Abs", extra=["StringOfReceivedData"])
    run_move(b, params(2))
    b.until_end()
    b.execute(False)
    b.scans(3)
    second = params(3, target={"X": 417.0, "Y": -122.0, "Z": 340.0, "RX": 180.0, "RY": 0.0, "RZ": 90.0})
    s1 = run_move(b, second)
    b.until_end()
    r = b.runner
    new, old = tmsct_reply("3,OK"), tag_notification(2)
    assert len(new) == 19 and len(old) == 26
    at_80 = r.first(lambda s: s["FB_step"] == 80, s1)
    assert at_80["StringOfReceivedData"] == new + old[len(new):]          # b'...OK,*5E\r\ne,*67\r\n'
    assert r.trace[-1]["Done"] and r.trace[-1]["CmdID_Ack"] == 3
    assert b.rx()[2] == thesis_frame(3, expected_script(second))


def test_ok_and_tag_in_one_segment_busy_forever(bench):
    """sysmac.md 8.5 (one receive per reply) with step 90's SktClearBuf: if the OK and the tag
    notification arrive in one TCP segment (a motion shorter than the PLC's reaction), step 70
    reads both, step 80 sees OK, step 90 clears the buffer and step 100 waits forever for a tag
    that was already read.  Robot side: our own socket server sending both in one write."""
    p = params(4)
    frame = thesis_frame(4, expected_script(p))

    def robot(f, i):
        if f == CHECK_LISTEN:
            return [LISTEN_OK]
        return [tmsct_reply("4,OK") + tag_notification(4)]
    b = bench("Abs", robot="fake", responder=robot, extra=["StringOfReceivedData"])
    s0 = run_move(b, p)
    b.until(lambda s: s["FB_step"] == 100, "step 100")
    b.scans(1500)
    r = b.runner
    assert b.fake.frames == [CHECK_LISTEN, frame]
    assert bytes(b.fake.received) == CHECK_LISTEN + frame      # nothing else on the wire (no 16#00)
    at_80 = r.first(lambda s: s["FB_step"] == 80, s0)
    assert at_80["StringOfReceivedData"] == tmsct_reply("4,OK") + tag_notification(4)
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0)]
    assert all(s["FB_step"] == 100 and s["WaitingReturn"] for s in r.trace[-1000:])


def test_silent_robot_busy_forever_8_6(bench):
    """sysmac.md 8.6: TCP_Rcv_TimeOut 0 and no timer: a robot that never answers keeps the FB
    Busy (and CBT.WaitingReturn TRUE) for ever - here 5 s of VM time."""
    b = bench("Abs", robot="fake")
    s0 = run_move(b, params(5))
    b.scans(5000)
    r = b.runner
    assert len(b.wait_rx(2)) == 2
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0)]
    assert all(s["FB_step"] == 70 and s["WaitingReturn"] for s in r.trace[-4900:])


def test_exit_node_with_queuetag_ok_after_drain(bench):
    """ExitNode without blending sends PTP + QueueTag + ScriptExit().  With the spec's default
    (tm_protocol.md §4.6/§11 #5: the OK of a ScriptExit() script comes after the motion queue
    drained) the tag notification precedes the OK: step 80 skips the TMSTA (back to 70), takes the
    OK, step 90 clears, step 100 then waits for a tag that has passed -> Busy for ever.  With a
    robot that answers OK at once the FB completes."""
    p = params(6, exit_node=True)
    b = bench("Abs")
    s0 = run_move(b, p)
    b.until(lambda s: s["FB_step"] == 100, "step 100")
    b.scans(1500)
    assert b.rx() == [CHECK_LISTEN, thesis_frame(6, expected_script(p))]
    assert b.tx()[1:3] == [tag_notification(6), tmsct_reply("6,OK")]
    assert b.runner.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0)]
    assert b.runner.trace[-1]["FB_step"] == 100

    b2 = bench("Abs", settings=emulator.EmulatorSettings(script_exit_ok_after_drain=False))
    s1 = run_move(b2, p)
    b2.until_end()
    assert b2.tx()[1:3] == [tmsct_reply("6,OK"), tag_notification(6)]
    assert b2.runner.states(OUTPUTS, s1)[-1] == (False, True, False, 0)
