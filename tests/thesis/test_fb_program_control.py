"""CBT_ProgramControl (thesis Annex A7, st_src/CBT_ProgramControl.st) against the TM emulator.

Pause() / Resume() as one-line scripts; the FB does not read the reply (step 60 -> 90,
sysmac.md 8.12) and does not check CBT.WaitingReturn (README '+').
"""

from __future__ import annotations

import emulator
from thesis_harness import (assert_done_once_after_drop, not_connected_states, CHECK_LISTEN, LISTEN_OK, OUTPUTS, RESET, frame_checksum, make_bench_fixture,
                            tag_notification, thesis_frame, tm_frame, tmsct_reply)

bench = make_bench_fixture()

# FB_step at the end of the Busy scans: 10 -> 20 -> 30 -> 40 -> 50 -> 60 -> 90 (no 70/80)
NORMAL_STEPS = [20, 30, 40, 50, 60, 90]


def params(cmd_id=5, command="Pause") -> dict:
    return {"CommandID": cmd_id, "Command": command}


def handle(b) -> int:
    return b.vm.get("T.Cobot.Socket.Handle")


def reply_left_unread(b) -> bool:
    """CBT_Connect's next 1 s status poll (SktGetTCPStatus) reports DatRcvFlag: unread bytes
    wait in the receive buffer (sysmac.md 8.12)."""
    b.scans(1100)
    return b.vm.get("T.Conn.Get_TCP_Status.DatRcvFlag")


# ------------------------------------------------------------------------------- frames


def test_pause_checksum_is_one_digit_for_every_id():
    """The XOR of 'TMSCT,9,<id>,Pause(),' is below 16#10 for every CommandID (2~9 per Table
    5.3.7.3, and any other): BYTE_TO_STRING makes it one digit (sysmac.md 8.2), e.g. ID 5 sends
    '*2' where tm_protocol.md §9.1 has '$TMSCT,9,5,Pause(),*02'."""
    assert b"$TMSCT,9,5,Pause(),*02\r\n" == thesis_frame(5, "Pause()").replace(b"*2", b"*02")
    for cmd_id in range(0, 100):
        frame = thesis_frame(cmd_id, "Pause()")
        assert frame_checksum(frame) < 0x10, cmd_id
    assert thesis_frame(5, "Pause()") == b"$TMSCT,9,5,Pause(),*2\r\n"


def test_pause_rejected_by_robot_yet_done(bench):
    """Default robot (one-digit checksum -> CPERR 01, tm_protocol.md §11 #9): the Pause never
    happens, but the FB reports Done - it never reads the reply (sysmac.md 8.12), which stays in
    the receive buffer.  Done three scans after the send completes (60 -> 90 -> ToDone -> state 5)."""
    b = bench("Prg")
    s0 = b.start_with(params(5, "Pause"))
    b.until_end()
    b.scans(20)
    r = b.runner
    assert b.wait_rx(2) == [CHECK_LISTEN, b"$TMSCT,9,5,Pause(),*2\r\n"]
    assert b.wait_tx(2) == [LISTEN_OK, tm_frame("CPERR", "01")]
    assert b.emulator.snapshot()["paused"] is False
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    assert r.busy_steps(s0) == NORMAL_STEPS
    at_90 = r.first(lambda s: s["FB_step"] == 90, s0)
    assert r.first(lambda s: s["Done"], s0).scan - at_90.scan == 3
    assert not any(s["WaitingReturn"] for s in r.since(s0))     # ProgramControl never sets it
    assert reply_left_unread(b)                                   # the CPERR is left unread


def test_resume_frame_matches_spec_vector(bench):
    """Resume() has a two-digit checksum: the frame is exactly tm_protocol.md §9.1's vector."""
    b = bench("Prg")
    s0 = b.start_with(params(6, "Resume"))
    b.until_end()
    b.scans(20)
    assert b.wait_rx(2) == [CHECK_LISTEN, b"$TMSCT,10,6,Resume(),*52\r\n"]
    assert b.rx()[1] == thesis_frame(6, "Resume()")
    assert b.wait_tx(2)[1] == tmsct_reply("6,OK") == b"$TMSCT,4,6,OK,*5B\r\n"
    assert b.runner.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    assert reply_left_unread(b)


def test_pause_and_resume_during_motion(bench):
    """With a robot that accepts one-digit checksums: Pause while CBT_MoveAbsolute waits for its
    tag (WaitingReturn TRUE is ignored by ProgramControl, README '+') freezes the motion - the
    move stays Busy; Resume completes it and the move reports Done (thesis l.3628)."""
    b = bench("Prg", settings=emulator.EmulatorSettings(accept_one_digit_checksum=True))
    b.runner.watch.update({f"Abs{k}": f"T.Abs.{k}" for k in OUTPUTS + ("FB_step",)})
    b.params({"CommandID": 2, "MovementCommand": "PTP", "DataFormat": "CPP_Abs", "TargetPosition.X": 417.0,
              "TargetPosition.Y": -122.0, "TargetPosition.Z": 330.0, "TargetPosition.RX": 180.0,
              "TargetPosition.RZ": 90.0, "Speed": 10, "AccelTime": 150}, inst="Abs")
    b.execute(True, inst="Abs")
    b.until(lambda s: s["AbsFB_step"] == 100, "move waiting for its tag")
    s0 = b.start_with(params(5, "Pause"))
    b.until_end()
    b.execute(False)
    b.scans(1500)
    assert b.emulator.snapshot()["paused"] is True
    assert b.runner.trace[-1]["AbsBusy"] and b.runner.trace[-1]["WaitingReturn"]
    s1 = b.start_with(params(6, "Resume"))
    b.until(lambda s: s["AbsDone"], "move Done")
    r = b.runner
    assert b.emulator.snapshot()["paused"] is False
    assert r.states(OUTPUTS, s0)[:3] == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]
    assert r.first(lambda s: s["Done"], s1).scan < r.first(lambda s: s["AbsDone"], s1).scan
    assert [f for f in b.rx() if b"Pause" in f or b"Resume" in f] == [
        b"$TMSCT,9,5,Pause(),*2\r\n", b"$TMSCT,10,6,Resume(),*52\r\n"]
    assert tag_notification(2) in b.tx()


# ------------------------------------------------------------------------------- errors


def test_robot_error_reply_not_noticed(bench):
    """The robot rejects the script (ERROR;1) but the FB does not read replies: Done (8.12)."""
    b = bench("Prg", faults=["error"])
    s0 = b.start_with(params(6, "Resume"))
    b.until_end()
    b.scans(10)
    assert b.wait_tx(2)[1] == tmsct_reply("6,ERROR;1")
    assert b.runner.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, True, False, 0)]


def test_send_error_after_reset_16_60(bench):
    """Connection reset by the robot before the command: CBT_Connect does not notice (8.10),
    the send in step 60 fails -> 16#60 'TCP send error'."""
    b = bench("Prg", robot="fake")
    b.fake.push(RESET)
    b.scans(20)
    assert b.runner.trace[-1]["Connected"]
    s0 = b.start_with(params(6, "Resume"))
    b.until_end(max_scans=2000)
    r = b.runner
    assert r.states(OUTPUTS, s0) == [(False, False, False, 0), (True, False, False, 0), (False, False, True, 0x60)]
    assert b.get("ErrorDescrip") == b"TCP send error"
    assert r.trace[-1]["Connected"]
    assert b.fake.frames == [CHECK_LISTEN]


def test_execute_dropped_while_busy(bench):
    b = bench("Prg")
    s0 = b.start_with(params(6, "Resume"))
    b.scans(1)
    b.execute(False)
    b.until(lambda s: s["Done"], "Done")
    b.scans(2)
    assert_done_once_after_drop(b.runner, s0)


def test_not_connected_16_99(bench):
    """Step 10 sets 16#10 'Robot not connected'; the check above the state diagram sets 16#99
    every scan and wins (README '+')."""
    b = bench("Prg", do_connect=False)
    s0 = b.start_with(params())
    b.scans(4)
    assert b.runner.output_states(s0) == not_connected_states(2)
    assert b.get("ErrorDescrip") == b"Robot not connected"


def test_unread_reply_discarded_by_next_fb_clear_buffer(bench):
    """sysmac.md 8.12: the CPERR answering the Pause stays buffered until the next FB's
    SktClearBuf (step 20): CBT_ChangeBase then reads only its own OK and completes."""
    b = bench("Prg")
    b.start_with(params(5, "Pause"))
    b.until_end()
    b.execute(False)
    assert reply_left_unread(b)
    b.runner.watch.update({f"Base{k}": f"T.Base.{k}" for k in OUTPUTS + ("StringOfReceivedData",)})
    b.params({"CommandID": 3, "Transformation.Z": 10.0}, inst="Base")
    s1 = b.execute(True, inst="Base")
    b.until(lambda s: s["BaseDone"] or s["BaseError"], "ChangeBase end")
    r = b.runner
    assert r.states(tuple(f"Base{k}" for k in OUTPUTS), s1)[-1] == (False, True, False, 0)
    assert r.trace[-1]["BaseStringOfReceivedData"] == tmsct_reply("3,OK")
    assert b.rx()[2] == thesis_frame(3, "ChangeBase(+0,+0,+10,+0,+0,+0)")
