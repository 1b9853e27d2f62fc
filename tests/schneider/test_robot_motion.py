"""The Schneider IF_RobotMotion-style library on a TM (st_src/schneider) against the emulated robot
in lockstep: the connected path as queued TM motions with QueueTags, the coordinate-system change
of ChangeCoordinateSystem2 queued as ChangeBase at the requested segment boundary, every
diagnostic of the seed's table under its documented cause, tracking (which a TM cannot do), and
the issue's bad input (ids and offsets out of range, no path, a segment id never queued, the
connection lost mid-path)."""

from __future__ import annotations

import subprocess
import sys

import pytest

import emulator
from emulator.motion import matrix_to_pose
from robotlibs_helpers import PNP_TARGETS, REPO, motion_commands, script_of, statements, tm_frame
from schneider_harness import (PICK, SchneiderBench, change, execute, move, move_c, set_cs, set_value)

OK = ("Ok", "Ok", "")


@pytest.fixture
def bench():
    made = []

    def make(**kw):
        b = SchneiderBench(**kw)
        made.append(b)
        return b
    yield make
    for b in made:
        b.close()


def robot_frame_tcp(b) -> list[float]:
    """The TCP in the robot frame (Cell.pose is in the robot's current base)."""
    return list(matrix_to_pose(b.robot().executor.current_tcp()))


def motion_frames(b) -> list[str]:
    return [script_of(f)[1] for f in b.rx() if f.startswith(b"$TMSCT") and (b"PTP" in f or b"Line" in f)]


def user_frame(b, n: int, frame) -> None:
    b.set_many(f"S.Robot.Cfg.astUserFrame[{n}]", dict(zip(("lrX", "lrY", "lrZ", "lrRx", "lrRy", "lrRz"), frame)))
    b.set(f"S.Robot.Cfg.axUserFrameConfigured[{n}]", True)


def pick_path(b, hold: bool = False):
    """The demo's pick path (segments 1..3, 100 mm each after the first) issued in one cycle."""
    commands = ([execute(False)] if hold else []) + [move("MovePTP", i + 1, t) for i, t in enumerate(PICK)]
    return b.issue(*commands)[1 if hold else 0:]


# ------------------------------------------------------------------------- the connected path


def test_segments_go_out_one_frame_each_with_their_queue_tag(bench):
    b = bench()
    b.watch = {"current": "S.Robot.udiCurrentSegmentId"}
    assert pick_path(b) == [("Ok", "NewConnectedPath", "New connected path"), OK, OK]
    b.until_path_end()
    assert b.path_diag() == OK and b.get("S.Robot.udiSegmentsDone") == 3
    sent = [f for f in b.rx() if f.startswith(b"$TMSCT") and b"PTP" in f]
    assert sent[0] == tm_frame("TMSCT", "1,PTP(\"CPP\",400.00,-150.00,300.00,180.00,0.00,90.00,50,200,0,false)\r\n"
                                        "QueueTag(1,0)")
    assert [statements(script_of(f)[1])[-1] for f in sent] == [("QueueTag", [1.0, 0.0]), ("QueueTag", [2.0, 0.0]),
                                                               ("QueueTag", [3.0, 0.0])]
    # queued: all three were on the robot before the first one finished
    first_tag = next(f.t_ns for f in b.transport.frames if f.direction == "tx" and b",01,01,true" in f.data)
    last_sent = [f.t_ns for f in b.transport.frames if f.direction == "rx" and b"PTP" in f.data][-1]
    assert last_sent < first_tag
    currents = [s["current"] for s in b.samples]
    assert [c for i, c in enumerate(currents) if i == 0 or c != currents[i - 1]] == [0, 1, 2, 3, 0]
    assert b.pose()[:3] == pytest.approx(list(PICK[2][:3]), abs=0.02)


def test_movel_is_a_tm_line_with_the_space_dynamics_and_zone(bench):
    b = bench()
    assert b.issue(set_value("SetMaxVelocity", "Space", 200.0), set_value("SetMaxAcceleration", "Space", 1000.0),
                   move("MoveL", 7, PICK[0], zone=5.0))[2][:2] == ("Ok", "NewConnectedPath")
    b.until_path_end()
    assert motion_frames(b) == ['Line("CAR",400.00,-150.00,300.00,180.00,0.00,90.00,200,200,5.00,true)\r\nQueueTag(1,0)']


def test_a_new_connected_path_after_the_robot_finished(bench):
    b = bench()
    pick_path(b)
    b.until_path_end()
    assert b.issue(move("MovePTP", 1, PNP_TARGETS[3]))[0][:2] == ("Ok", "NewConnectedPath")   # id 1 again: a new path
    b.until_path_end()
    assert len(motion_frames(b)) == 4


def test_execute_false_holds_the_segments_until_execute_true(bench):
    b = bench()
    assert pick_path(b, hold=True)[0][1] == "NewConnectedPath"
    b.scan(200)
    assert motion_frames(b) == [] and b.get("S.Robot.xPathActive")
    assert b.issue(execute(True)) == [OK]
    b.until_path_end()
    assert len(motion_frames(b)) == 3 and b.path_diag() == OK


# ------------------------------------------------------------------------- coordinate-system change


@pytest.mark.parametrize(("start", "end", "before"), [
    ((2, 0.0), (2, 0.0), 2),          # offset 0.0: at the start of segment 2
    ((2, 40.0), (3, -10.0), 3),       # inside segment 2: the next boundary, before segment 3
    ((2, -100.0), (2, 0.0), 2),       # -length from the end = the start of segment 2
])
def test_change_is_queued_as_change_base_at_the_segment_boundary(bench, start, end, before):
    b = bench()
    user_frame(b, 1, (10.0, 20.0, 0.0, 0.0, 0.0, 0.0))
    pick_path(b, hold=True)
    assert b.issue(set_cs("User1"), change(*start, *end), execute(True)) == [OK, OK, OK]
    b.until_path_end()
    assert b.path_diag() == OK
    scripts = motion_frames(b)
    assert len(scripts) == 3
    for i, script in enumerate(scripts, start=1):
        names = [name for name, _ in statements(script)]
        assert names == (["ChangeBase", "PTP", "QueueTag"] if i == before else ["PTP", "QueueTag"])
    assert statements(scripts[before - 1])[0] == ("ChangeBase", [10.0, 20.0, 0.0, 0.0, 0.0, 0.0])
    # the robot went to the last target in the user frame: 10 mm / 20 mm off in the robot frame
    assert robot_frame_tcp(b)[:3] == pytest.approx([PICK[2][0] + 10.0, PICK[2][1] + 20.0, PICK[2][2]], abs=0.05)


def test_change_while_the_robot_moves_and_back_to_the_robot_frame(bench):
    b = bench()
    user_frame(b, 2, (0.0, 0.0, 50.0, 0.0, 0.0, 0.0))
    pick_path(b)                                       # sent at once (no Execute FALSE)
    # next cycle: segment 1 is being sent, segment 3 not yet
    assert b.issue(set_cs("User2"), change(3, 0.0, 3, 0.0)) == [OK, OK]
    b.until_path_end()
    assert [n for n, _ in statements(motion_frames(b)[2])] == ["ChangeBase", "PTP", "QueueTag"]
    assert robot_frame_tcp(b)[2] == pytest.approx(PICK[2][2] + 50.0, abs=0.05)
    # the next path changes back to the robot frame at its first segment
    b.issue(move("MovePTP", 1, PNP_TARGETS[3]), move("MovePTP", 2, PNP_TARGETS[4]))
    assert b.issue(set_cs("Robot"), change(2, 0.0, 2, 0.0)) == [OK, OK]
    b.until_path_end()
    assert statements(motion_frames(b)[4])[0] == ("ChangeBase", ["RobotBase"])
    assert robot_frame_tcp(b)[:3] == pytest.approx(list(PNP_TARGETS[4][:3]), abs=0.05)


def test_of_two_changes_at_one_boundary_the_later_one_is_sent(bench):
    b = bench()
    user_frame(b, 1, (10.0, 20.0, 0.0, 0.0, 0.0, 0.0))
    pick_path(b, hold=True)
    assert b.issue(set_cs("User1"), change(3, 0.0, 3, 0.0), set_cs("Robot"), change(3, 0.0, 3, 0.0),
                   execute(True)) == [OK] * 5
    b.until_path_end()
    assert [n for n, _ in statements(motion_frames(b)[2])] == ["ChangeBase", "PTP", "QueueTag"]
    assert statements(motion_frames(b)[2])[0] == ("ChangeBase", ["RobotBase"])


def test_without_set_coordinate_system_the_last_one_stays(bench):
    b = bench()
    pick_path(b, hold=True)
    diag = b.issue(change(2, 0.0, 2, 0.0), execute(True))[0]
    assert diag[:2] == ("Ok", "Ok") and "stays" in diag[2]
    b.until_path_end()
    assert all("ChangeBase" not in s for s in motion_frames(b))


# ------------------------------------------------------------------------- the seed's diagnostics, each under its cause


def test_interface_invalid_without_the_tm_link(bench):
    b = bench(connect=False)
    expected = ("UnexpectedProgramBehavior", "InterfaceInvalid", "TM link not connected or not in the Listen node")
    assert b.issue(change(1, 0.0, 1, 0.0), move("MovePTP", 1, PICK[0])) == [expected, expected]


def test_external_position_source_configured(bench):
    b = bench()
    pick_path(b, hold=True)
    b.set("S.Robot.Cfg.xExternalPositionSource", True)
    d = b.issue(change(2, 0.0, 2, 0.0), move("MovePTP", 9, PICK[0]))
    assert [x[:2] for x in d] == [("ExecutionAborted", "ExternalPositionSourceConfigured")] * 2


def test_command_refused_when_a_move_is_issued_in_the_same_cycle(bench):
    b = bench()
    d = b.issue(move("MovePTP", 1, PICK[0]), move("MovePTP", 2, PICK[1]), change(2, 0.0, 2, 0.0))
    assert d[2] == ("ExecutionAborted", "CommandRefused", "A move command was issued in the same cycle")
    assert b.issue(change(2, 0.0, 2, 0.0))[0][:2] == ("Ok", "Ok")      # one cycle later: accepted


def test_command_refused_whatever_the_call_order(bench):
    """Issue 31 item 4: change-then-move in one cycle was accepted on both sides, move-then-change
    refused. Whichever comes second is refused now; a refused change does not refuse the move."""
    b = bench()
    pick_path(b, hold=True)
    d = b.issue(change(2, 0.0, 2, 0.0), move("MovePTP", 4, PICK[0]))
    assert d[0][:2] == ("Ok", "Ok")
    assert d[1] == ("ExecutionAborted", "CommandRefused", "A coordinate-system change was issued in the same cycle")
    assert b.issue(move("MovePTP", 4, PICK[0]))[0][:2] == ("Ok", "Ok")      # the next cycle: accepted
    d = b.issue(change(99, 0.0, 2, 0.0), move("MovePTP", 5, PICK[1]))      # the change refused: the move stands
    assert d[0][1] == "StartSegmentIdNotFound" and d[1][:2] == ("Ok", "Ok")


@pytest.mark.parametrize(("start_offset", "end"), [(40.0, (3, 0.0)), (-10.0, (3, 0.0))])
def test_change_inside_the_last_segment_is_sent_alone(bench, start_offset, end):
    """Issue 31 item 4: a change starting inside the last segment answered Ok/Ok and was never sent
    when no segment followed; the next path then ran in the old frame (410, 170 instead of 400, 150).
    Its ChangeBase now goes alone once the segments are on the robot."""
    b = bench()
    user_frame(b, 1, (10.0, 20.0, 0.0, 0.0, 0.0, 0.0))
    b.issue(set_cs("User1"))
    pick_path(b)
    b.issue(set_cs("Robot"))                         # a change to the robot frame, 40 mm into segment 3
    assert b.issue(change(3, start_offset, *end))[0] == OK
    b.until_path_end()
    assert b.path_diag() == OK
    alone = [script_of(f)[1] for f in b.rx() if f.startswith(b"$TMSCT")][-1]
    assert statements(alone) == [("ChangeBase", ["RobotBase"])]
    b.issue(move("MovePTP", 1, (400.0, 150.0, 300.0, 180.0, 0.0, 90.0)))
    b.until_path_end()
    assert robot_frame_tcp(b)[:3] == pytest.approx([400.0, 150.0, 300.0], abs=0.05)


def test_change_after_segment_slot_15_is_sent(bench):
    """Issue 31 item 4: a change in segment slot 15 has boundary 16, which no segment index matches."""
    b = bench()
    user_frame(b, 1, (10.0, 20.0, 0.0, 0.0, 0.0, 0.0))
    b.issue(execute(False))
    b.issue(*[move("MovePTP", i + 1, PICK[i % 3]) for i in range(8)])
    b.issue(*[move("MovePTP", i + 9, PICK[(i + 8) % 3]) for i in range(7)], move("MovePTP", 16, PICK[1]))
    assert b.issue(set_cs("User1"), change(16, 50.0, 16, 0.0), execute(True)) == [OK, OK, OK]   # 16: 100 mm
    b.until_path_end(60000)
    assert b.path_diag() == OK
    assert statements(script_of([f for f in b.rx() if f.startswith(b"$TMSCT")][-1])[1])[0][0] == "ChangeBase"
    b.issue(move("MovePTP", 1, PICK[0]))
    b.until_path_end()
    assert robot_frame_tcp(b)[:3] == pytest.approx([PICK[0][0] + 10.0, PICK[0][1] + 20.0, PICK[0][2]], abs=0.05)


def test_move_c_is_a_tm_circle(bench):
    """Issue 31 item 4: MoveC builds the TM Circle() as CBT_MoveCircle sends it (CAP, Space dynamics,
    blend %, arc angle 0) and the robot goes round the arc to the target."""
    b = bench()
    start = (400.0, -150.0, 300.0, 180.0, 0.0, 90.0)
    b.issue(move("MoveL", 1, start))
    d = b.issue(move_c(2, (450.0, -100.0, 300.0), (400.0, -50.0, 300.0, 180.0, 0.0, 90.0)))
    assert d == [OK]
    b.until_path_end()
    assert b.path_diag() == OK
    circle = [args for name, args in motion_commands(b.rx()) if name == "Circle"]
    assert circle == [["CAP", 450.0, -100.0, 300.0, 180.0, 0.0, 90.0, 400.0, -50.0, 300.0, 180.0, 0.0, 90.0,
                       250.0, 200.0, 0.0, 0.0, False]]
    assert robot_frame_tcp(b)[:3] == pytest.approx([400.0, -50.0, 300.0], abs=0.05)
    # the segment length counts the arc's chords: 2 x 70.71 mm, a 100 mm offset is inside it
    assert b.get("S.Robot.astSegment[1].lrLength") == pytest.approx(2 * 50 * 2 ** 0.5, abs=0.01)


@pytest.mark.parametrize(("zone", "expected"), [(-1.0, "CommandRefused"), (100.5, "CommandRefused")])
def test_move_c_zone_is_a_percentage(bench, zone, expected):
    b = bench()
    d = b.issue(move_c(1, (450.0, -100.0, 300.0), (400.0, -50.0, 300.0, 180.0, 0.0, 90.0), zone))
    assert d[0][:2] == ("ExecutionAborted", expected)


@pytest.mark.parametrize(("command", "expected"), [
    (change(0, 0.0, 1, 0.0), ("InputParameterInvalid", "StartSegmentIdRange")),
    (change(1, 0.0, 0, 0.0), ("InputParameterInvalid", "EndSegmentIdRange")),
    (change(99, 0.0, 2, 0.0), ("ExecutionAborted", "StartSegmentIdNotFound")),       # never queued
    (change(2, 0.0, 99, 0.0), ("ExecutionAborted", "EndSegmentIdNotFound")),
    (change(2, 100.5, 3, 0.0), ("InputParameterInvalid", "StartOffsetRange")),       # segment 2 is 100 mm
    (change(2, -100.5, 3, 0.0), ("InputParameterInvalid", "StartOffsetRange")),
    (change(2, 0.0, 3, 101.0), ("InputParameterInvalid", "EndOffsetRange")),
    (change(2, 0.0, 3, -101.0), ("InputParameterInvalid", "EndOffsetRange")),
    (change(1, 1.0, 1, 0.0), ("InputParameterInvalid", "StartOffsetRange")),         # segment 1: no known start, length 0
    (change(3, 50.0, 2, 0.0), ("ExecutionAborted", "PathPositionEndInvalid")),       # end before start
    (change(3, 0.0, 2, 0.0), ("Ok", "Ok")),                                          # end of 2 = start of 3
    (change(2, 60.0, 2, 50.0), ("ExecutionAborted", "PathPositionEndInvalid")),
    (change(2, 100.0, 3, 0.0), ("Ok", "Ok")),                                        # |offset| = length is valid
])
def test_input_checks(bench, command, expected):
    b = bench()
    pick_path(b, hold=True)
    assert b.issue(set_cs("Robot"), command)[1][:2] == expected


def test_no_connected_path_available(bench):
    b = bench()
    assert b.issue(change(1, 0.0, 1, 0.0))[0][:2] == ("ExecutionAborted", "NoConnectedPathAvailable")   # empty path
    pick_path(b)
    b.until_path_end()
    assert b.issue(change(3, 0.0, 3, 0.0))[0][:2] == ("ExecutionAborted", "NoConnectedPathAvailable")   # finished


def test_path_position_start_already_passed(bench):
    b = bench()
    pick_path(b)
    b.until(lambda: b.get("S.Robot.udiCurrentSegmentId") == 2, 5000, "segment 2 running")
    d = b.issue(set_cs("Robot"), change(2, 0.0, 3, 0.0), change(1, 0.0, 3, 0.0))
    assert d[1] == ("ExecutionAborted", "PathPositionStartAlreadyPassed", "Segment 2 already sent to the robot")
    assert d[2][:2] == ("ExecutionAborted", "PathPositionStartAlreadyPassed")


def test_path_position_start_already_passed_inside_a_finished_segment(bench):
    b = bench()
    pick_path(b)
    b.until(lambda: b.get("S.Robot.udiCurrentSegmentId") == 3, 5000, "segment 3 running")
    # 50 mm into segment 2 would change at the 2/3 boundary, but the robot finished segment 2
    assert b.issue(set_cs("Robot"), change(2, 50.0, 3, 0.0))[1] == (
        "ExecutionAborted", "PathPositionStartAlreadyPassed", "Segment 2 already finished")


def test_path_position_start_invalid_before_a_previous_change(bench):
    b = bench()
    pick_path(b, hold=True)
    d = b.issue(set_cs("Robot"), change(3, 0.0, 3, 0.0), set_cs("Robot"), change(2, 50.0, 3, 0.0), set_cs("Robot"),
                change(3, 0.0, 3, 0.0))
    assert d[1] == OK and d[3][:2] == ("ExecutionAborted", "PathPositionStartInvalid") and d[5] == OK


def test_no_more_tracking_events_after_four_pending_changes(bench):
    b = bench()
    pick_path(b, hold=True)
    d = b.issue(*[c for _ in range(4) for c in (set_cs("Robot"), change(3, 0.0, 3, 0.0))])
    assert all(x == OK for x in d)
    assert b.issue(set_cs("Robot"), change(3, 0.0, 3, 0.0))[1][:2] == ("ExecutionAborted", "NoMoreTrackingEventsAvailable")


def test_tracking_max_acceleration_resultant_range_then_no_tracking_events(bench):
    b = bench()
    pick_path(b, hold=True)
    d = b.issue(set_cs("LinearTracking1"), change(2, 0.0, 3, 0.0))
    assert d[0] == OK and d[1] == ("ExecutionAborted", "MaxAccelerationResultantRange",
                                   "SetMaxAccelerationResultant(Tracking) not called")
    d = b.issue(set_value("SetMaxAccelerationResultant", "Tracking", 2000.0), set_cs("LinearTracking2"),
                change(2, 0.0, 3, 0.0))
    assert d[0] == OK and d[2] == ("ExecutionAborted", "NoMoreTrackingEventsAvailable",
                                   "A TM has no tracking events (no tracking systems)")


@pytest.mark.parametrize(("component", "value", "expected"), [
    ("Tracking", 0.0, ("InputParameterInvalid", "MaxAccelerationResultantRange")),
    ("Tracking", -1.0, ("InputParameterInvalid", "MaxAccelerationResultantRange")),
    ("Tracking", 0.1, ("Ok", "Ok")),
    ("Space", -0.1, ("InputParameterInvalid", "MaxAccelerationResultantRange")),
    ("Space", 0.0, ("Ok", "Ok")),                  # 0.0 disables the limitation
    ("Axes", 1.0, ("InputParameterInvalid", "MaxAccelerationResultantRange")),
])
def test_set_max_acceleration_resultant_ranges(bench, component, value, expected):
    b = bench()
    assert b.issue(set_value("SetMaxAccelerationResultant", component, value))[0][:2] == expected


def test_unexpected_feedback_when_the_robot_refuses_a_segment(bench):
    b = bench(faults=["error:2"])
    pick_path(b)
    b.until_path_end()
    diag, ext, msg = b.path_diag()
    assert (diag, ext) == ("UnexpectedProgramBehavior", "UnexpectedFeedback") and "Command rejected" in msg
    refused = int(msg.split()[1].rstrip(":"))
    assert b.get("S.Robot.udiFaultSegmentId") == refused
    # nothing after the refused segment was sent; the robot was stopped
    assert len(motion_frames(b)) == refused
    assert any(b"StopAndClearBuffer" in f for f in b.rx())
    assert b.issue(change(3, 0.0, 3, 0.0))[0][:2] == ("ExecutionAborted", "NoConnectedPathAvailable")


def test_unexpected_feedback_when_the_robot_reports_a_motion_failed(bench):
    b = bench(faults=["tag_false"])
    pick_path(b)
    b.until_path_end()
    assert b.path_diag() == ("UnexpectedProgramBehavior", "UnexpectedFeedback", "The robot reports segment 1 failed")
    assert b.get("S.Robot.udiFaultSegmentId") == 1


def test_connection_lost_mid_path_is_reported_and_no_motion_half_sent(bench):
    b = bench(faults=["drop:20"])
    pick_path(b)
    b.until_path_end()
    assert b.path_diag() == ("UnexpectedProgramBehavior", "InterfaceInvalid",
                             "Connection to the TM lost: connected path aborted")
    states = [b.get(f"S.Robot.astSegment[{i}].iState") for i in range(3)]
    assert 7 in states and 6 not in states[states.index(7):]
    for frame in b.rx():                              # every frame the robot got is whole (spec section 2)
        header, _, rest = frame[1:].partition(b",")
        length, _, rest = rest.partition(b",")
        assert frame == tm_frame(header.decode(), rest[:int(length)].decode())
    # the path is over: new commands see no path (and no link until reconnected)
    assert b.issue(change(3, 0.0, 3, 0.0))[0][1] in ("NoConnectedPathAvailable", "InterfaceInvalid")


# ------------------------------------------------------------------------- bad move input


@pytest.mark.parametrize(("commands", "message"), [
    ([move("MovePTP", 0, PICK[0])], "Segment Id must be > 0"),
    ([move("MovePTP", 1, PICK[0]), move("MovePTP", 1, PICK[1])], "Segment Id already in the connected path"),
    ([move("MovePTP", 1, PICK[0], zone=101.0)], "Blending zone out of range"),
    ([move("MoveL", 1, PICK[0], zone=-1.0)], "Blending zone out of range"),
])
def test_bad_move_input_is_refused_and_nothing_sent(bench, commands, message):
    b = bench()
    d = b.issue(*commands)
    assert d[-1] == ("ExecutionAborted", "CommandRefused", message)
    b.scan(300)
    assert len(motion_frames(b)) == len(commands) - 1


def test_a_connected_path_holds_sixteen_segments(bench):
    b = bench()
    b.issue(execute(False))
    for first in range(0, 16, 8):
        assert all(d[0] == "Ok" for d in b.issue(*[move("MovePTP", first + i + 1, PICK[(first + i) % 3]) for i in range(8)]))
    assert b.issue(move("MovePTP", 17, PICK[0]))[0] == ("ExecutionAborted", "CommandRefused",
                                                        "Connected path full (16 segments)")


@pytest.mark.parametrize(("op", "component", "value"), [
    ("SetMaxVelocity", "Axes", 0.0), ("SetMaxVelocity", "Axes", 100.5), ("SetMaxVelocity", "Space", 1100.5),
    ("SetMaxAcceleration", "Space", -5.0), ("SetMaxVelocity", "Tracking", 10.0),
])
def test_dynamics_out_of_range(bench, op, component, value):
    b = bench()
    assert b.issue(set_value(op, component, value))[0][:2] == ("InputParameterInvalid", "CommandRefused")


# ------------------------------------------------------------------------- the library


def test_library_is_lint_clean():
    run = subprocess.run([sys.executable, "-m", "stvm", "lint", "st_src/schneider"], cwd=REPO, capture_output=True,
                         text=True)
    assert run.returncode == 0, run.stdout + run.stderr


# ------------------------------------------------------------------------- emulator choices (docs/emulator.md)


@pytest.mark.parametrize("applies", [True, False])
def test_after_a_stop_the_coordinate_system_set_last_stays(bench, applies):
    """A refused segment stops the robot and drops the segment carrying a ChangeBase; whether the
    robot keeps that base is the emulator switch stop_applies_queued_frames. The link sends the
    coordinate system sent last again with the next segment after a stop, so the next path runs in it
    (seed: the robot stays in the coordinate system set last) under both choices."""
    b = bench(settings=emulator.EmulatorSettings(stop_applies_queued_frames=applies))
    user_frame(b, 1, (10.0, 20.0, 0.0, 0.0, 0.0, 0.0))
    pick_path(b, hold=True)
    b.issue(move("MovePTP", 4, (2000.0, 0.0, 300.0, 180.0, 0.0, 90.0)))     # unreachable: refused
    assert b.issue(set_cs("User1"), change(2, 0.0, 2, 0.0), execute(True)) == [OK, OK, OK]
    b.until_path_end()
    assert b.path_diag()[1] == "UnexpectedFeedback"
    b.scan(50)
    b.issue(move("MovePTP", 1, PICK[1]))
    b.until_path_end()
    assert b.path_diag() == OK
    assert statements(motion_frames(b)[-1])[0] == ("ChangeBase", [10.0, 20.0, 0.0, 0.0, 0.0, 0.0])
    assert robot_frame_tcp(b)[:3] == pytest.approx([PICK[1][0] + 10.0, PICK[1][1] + 20.0, PICK[1][2]], abs=0.05)


@pytest.mark.parametrize("reject", [False, True])
def test_a_zero_length_segment_completes_or_is_unexpected_feedback(bench, reject):
    b = bench(settings=emulator.EmulatorSettings(reject_zero_length_motion=reject))
    b.issue(move("MovePTP", 1, PICK[0]), move("MovePTP", 2, PICK[0]))
    b.until_path_end()
    assert b.path_diag()[:2] == (("UnexpectedProgramBehavior", "UnexpectedFeedback") if reject else ("Ok", "Ok"))
