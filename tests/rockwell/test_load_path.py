"""raM_Robot_Opr_LoadPath on a TM (st_src/rockwell) against the emulated robot in lockstep: the
seed's execution (1.5), queued loading through the device handler's buffer of 5, the MoveID of
the point that starts, each combination of move type, target type and interpolation (seed 1.3),
blending, configuration, frames; every seed 2.3 error code whose condition can arise on a TM, and
the issue's bad input (start index, number of moves, empty path, path longer than the array,
connection lost mid-path)."""

from __future__ import annotations

import math

import pytest

import emulator
from emulator.motion import Kinematics, matrix_to_pose
from robotlibs_helpers import PNP_TARGETS, motion_commands, script_of, tm_frame
from rockwell_harness import RockwellBench, cartesian, joints, pnp_point

HOME_JOINTS = (0.0, 0.0, 90.0, 0.0, 90.0, 0.0)


@pytest.fixture
def bench():
    made = []

    def make(**kw):
        b = RockwellBench(**kw)
        made.append(b)
        return b
    yield make
    for b in made:
        b.close()


def loaded(b) -> int:
    """Buffer points in use now (Sts.PointsInBuffer is the handler's count, one scan later)."""
    return sum(1 for i in range(5) if b.get(f"R.Robot.Buffer[{i}].State") != 0)


def until_end(b, inst="A", max_scans=30000):
    b.until(lambda: b.get(f"R.{inst}.Sts_PC") or b.get(f"R.{inst}.Sts_ER"), max_scans, f"{inst} end")
    return b.outputs(inst)


# ------------------------------------------------------------------------- normal execution


def test_pick_path_loads_in_one_scan_and_reports_each_point(bench):
    b = bench()
    b.path([pnp_point(i) for i in range(3)])
    b.watch = {"ActiveMoveID": "R.Robot.Sts.ActiveMoveID", "Active": "R.A.Sts_ActivePathPoint",
               "Pending": "R.A.Sts_PendingPathPoints", "IP": "R.A.Sts_IP", "PC": "R.A.Sts_PC", "DN": "R.A.Sts_DN",
               "AC": "R.A.Sts_AC", "InBuffer": "R.Robot.Sts.PointsInBuffer"}
    b.run("A", 0, 3)
    b.scan(1)
    first = b.samples[-1]
    assert first["IP"] and first["DN"] and not first["PC"] and loaded(b) == 3     # in one scan (seed 1.2)
    end = until_end(b)
    assert end["Sts_PC"] and not end["Sts_IP"] and not end["Sts_ER"] and end["Sts_EO"] and end["Sts_EN"]
    assert end["Sts_PendingPathPoints"] == 0 and end["Sts_MtdID"] == 1
    frames = b.rx()[1:]
    assert frames[0] == tm_frame("TMSCT", '1,ChangeTCP("NOTOOL")\r\nChangeBase("RobotBase")\r\n'
                                          'PTP("CPP",400.00,-150.00,300.00,180.00,0.00,90.00,50,200,0,false)\r\nQueueTag(1,0)')
    assert [script_of(f)[1] for f in frames[1:]] == [
        'PTP("CPP",400.00,-150.00,200.00,180.00,0.00,90.00,20,200,0,false)\r\nQueueTag(2,0)',
        'PTP("CPP",400.00,-150.00,300.00,180.00,0.00,90.00,20,200,0,false)\r\nQueueTag(3,0)']
    # all three sent before the first motion ended: the robot moved from point to point without waiting
    tags = [f.t_ns for f in b.transport.frames if f.direction == "tx" and b",01,0" in f.data]
    sent = [f.t_ns for f in b.transport.frames if f.direction == "rx" and b"PTP" in f.data]
    assert sent[-1] < tags[0]
    # MoveID reported when each point starts; active point, pending count
    starts = [(s["ActiveMoveID"], s["Active"], s["Pending"]) for s in b.samples if s["ActiveMoveID"]]
    runs = [v for i, v in enumerate(starts) if i == 0 or v != starts[i - 1]]
    assert runs == [(101, 0, 3), (102, 1, 2), (103, 2, 1)]
    # issue 31 item 3: once the path has ended no move is active (the last ID stayed before)
    assert b.samples[-1]["ActiveMoveID"] == 0 and b.samples[-1]["Active"] == -1
    assert b.pose()[:3] == pytest.approx(list(PNP_TARGETS[2][:3]), abs=0.02)


def test_buffer_of_five_refilled_as_points_complete(bench):
    b = bench()
    zs = [300.0, 290.0, 280.0, 270.0, 260.0, 250.0, 240.0, 230.0]
    b.path([cartesian((400.0, -150.0, z, 180.0, 0.0, 90.0), move_id=i + 1, speed=180.0, accel=1800.0)
            for i, z in enumerate(zs)])
    b.watch = {"InBuffer": "R.Robot.Sts.PointsInBuffer", "DN": "R.A.Sts_DN", "Pending": "R.A.Sts_PendingPathPoints"}
    b.run("A", 0, 8)
    b.scan(1)
    assert loaded(b) == 5 and not b.samples[-1]["DN"]
    end = until_end(b)
    assert end["Sts_PC"]
    assert max(s["InBuffer"] for s in b.samples) == 5
    dn = next(s for s in b.samples if s["DN"])
    assert dn["Pending"] == 5                     # the last 3 were loaded as the first 3 completed
    assert [args[3] for _, args in motion_commands(b.rx())] == zs


def test_second_instance_queues_behind_while_the_robot_moves(bench):
    b = bench()
    b.path([pnp_point(i) for i in range(6)])
    b.run("A", 0, 3)
    b.scan(100)                                   # point 0 is executing
    b.run("B", 3, 3)
    b.scan(1)
    assert b.get("R.B.Sts_IP") and b.get("R.B.Sts_MtdID") == 2
    until_end(b, "A")
    end = until_end(b, "B")
    assert end["Sts_PC"] and not b.get("R.A.Sts_ER")
    assert [args[1:4] for _, args in motion_commands(b.rx())] == [list(t[:3]) for t in PNP_TARGETS]
    assert b.pose()[:3] == pytest.approx(list(PNP_TARGETS[5][:3]), abs=0.02)


def test_move_id_zero_reports_the_method_id(bench):
    b = bench()
    b.path([pnp_point(0, move_id=0)])
    b.watch = {"ActiveMoveID": "R.Robot.Sts.ActiveMoveID"}
    b.run("A", 0, 1)
    until_end(b)
    assert {s["ActiveMoveID"] for s in b.samples} - {0} == {b.get("R.A.Sts_MtdID")}


# ------------------------------------------------------------------------- move, target, interpolation


def fk_pose(q) -> list[float]:
    return list(matrix_to_pose(Kinematics().fk(q)))


@pytest.mark.parametrize(("point", "script", "final"), [
    (joints((10, 0, 90, 0, 90, 0)),
     'PTP("JPP",10.00,0.00,90.00,0.00,90.00,0.00,50,200,0,false)', fk_pose((10, 0, 90, 0, 90, 0))),
    (joints((10, 0, 0, 0, 0, 0), move_type=1),
     'Move_PTP("JPP",10.00,0.00,0.00,0.00,0.00,0.00,50,200,0,false)', fk_pose((10, 0, 90, 0, 90, 0))),
    (cartesian((0, 0, -50, 0, 0, 0), move_type=1),
     'Move_PTP("CPP",0.00,0.00,-50.00,0.00,0.00,0.00,50,200,0,false)', [417.5, -122.3, 310.9, 180, 0, 90]),
    (cartesian((417.5, -122.3, 300.0, 180, 0, 90), interpolation=1, speed=200.0, accel=1000.0),
     'Line("CAR",417.50,-122.30,300.00,180.00,0.00,90.00,200,200,0,false)', [417.5, -122.3, 300.0, 180, 0, 90]),
    (cartesian((20, 0, 0, 0, 0, 0), interpolation=1, move_type=1, speed=200.0, accel=1000.0),
     'Move_Line("CAR",20.00,0.00,0.00,0.00,0.00,0.00,200,200,0,false)', [437.5, -122.3, 360.9, 180, 0, 90]),
])
def test_move_target_and_interpolation_types(bench, point, script, final):
    b = bench()
    b.path([point])
    b.run("A", 0, 1)
    assert until_end(b)["Sts_PC"]
    sent = [s for s in script_of(b.rx()[-1])[1].split("\r\n") if s.startswith(("PTP", "Move", "Line"))]
    assert sent == [script]
    assert b.pose() == pytest.approx(final, abs=0.02)


def test_joint_target_with_linear_interpolation_goes_through_forward_kinematics(bench):
    q = (10.0, 5.0, 80.0, 0.0, 95.0, 0.0)
    b = bench()
    p = joints(q, interpolation=1, speed=200.0, accel=1000.0)
    p.update({"OrientationSpeed": 90.0, "OrientationAcceleration": 450.0, "OrientationDeceleration": 450.0,
              "Pose.FrameType": 2, "Pose.RefFrameType": 1})
    b.path([p])
    b.run("A", 0, 1)
    assert until_end(b)["Sts_PC"]
    name, args = motion_commands(b.rx())[-1]
    assert name == "Line" and args[0] == "CAR"
    assert args[1:7] == pytest.approx(fk_pose(q), abs=0.006)     # the ST kinematics = the robot's
    assert b.robot().snapshot()["joints"] == pytest.approx(list(q), abs=0.05)


def test_blending_and_configuration_and_frames(bench):
    b = bench()
    b.set_many("R.Robot.Cfg.ToolFrames[2]", {"Z": 100.0})
    b.set("R.Robot.Cfg.ToolConfigured[2]", True)
    b.set_many("R.Robot.Cfg.UserFrames[3]", {"X": 10.0, "Rz": 90.0})
    b.set("R.Robot.Cfg.UserConfigured[3]", True)
    b.path([cartesian((417.5, -122.3, 330.0, 180, 0, 90), termination=6, tolerance=30.0, config=1 + 2 + 8),
            cartesian((-100.0, -400.0, 300.0, 180, 0, 0), interpolation=1, termination=6, tolerance=15.0,
                      frame_type=3, tool_id=2, ref_type=4, ref_id=3, speed=200.0, accel=1000.0),
            cartesian((-100.0, -400.0, 250.0, 180, 0, 0), interpolation=1, frame_type=3, tool_id=2, ref_type=4,
                      ref_id=3, speed=200.0, accel=1000.0)])
    b.run("A", 0, 3)
    assert until_end(b)["Sts_PC"]
    scripts = [script_of(f)[1] for f in b.rx()[1:]]
    assert scripts[0].split("\r\n")[2] == 'PTP("CPP",417.50,-122.30,330.00,180.00,0.00,90.00,50,200,30,true,1,3,5)'
    assert scripts[1].split("\r\n") == ["ChangeTCP(0.00,0.00,100.00,0.00,0.00,0.00)",
                                        "ChangeBase(10.00,0.00,0.00,0.00,0.00,90.00)",
                                        'Line("CAR",-100.00,-400.00,300.00,180.00,0.00,0.00,200,200,15.00,true)',
                                        "QueueTag(2,0)"]
    assert scripts[2].startswith('Line("CAR",-100.00,-400.00,250.00')      # same frames: not sent again
    snap = b.robot().snapshot()
    assert snap["pose"][:3] == pytest.approx([-100.0, -400.0, 250.0], abs=0.02)     # in the user frame


def test_blending_move_id(bench):
    b = bench()
    b.path([cartesian((417.5, -122.3, 300.0, 180, 0, 90), move_id=7, termination=6, tolerance=50.0),
            cartesian((417.5, -122.3, 250.0, 180, 0, 90), move_id=8)])
    b.watch = {"Active": "R.Robot.Sts.ActiveMoveID", "Blending": "R.Robot.Sts.BlendingMoveID"}
    b.run("A", 0, 2)
    assert until_end(b)["Sts_PC"]
    pairs = {(s["Active"], s["Blending"]) for s in b.samples}
    assert (7, 8) in pairs and (8, 7) not in pairs and (8, 0) in pairs


def test_zero_dynamics_keep_the_last_valid_values(bench):
    b = bench()
    second = pnp_point(1)
    second.update({"Speed": 0.0, "Acceleration": 0.0, "Deceleration": 0.0})
    b.path([pnp_point(0), second])
    b.run("A", 0, 2)
    assert until_end(b)["Sts_PC"]
    assert [args[7:9] for _, args in motion_commands(b.rx())] == [[50.0, 200.0], [50.0, 200.0]]


# ------------------------------------------------------------------------- rung, stop, faults


def test_rung_false_withdraws_what_was_not_sent(bench):
    b = bench()
    b.path([cartesian((400.0, -150.0, 300.0 - 10 * i, 180, 0, 90), speed=36.0, accel=180.0) for i in range(8)])
    b.run("A", 0, 8)
    b.scan(60)                                     # 5 loaded, sent one by one
    b.set("R.AEnable", False)
    b.scan(1)
    out = b.outputs()
    assert not out["Sts_EO"] and not out["Sts_EN"] and not out["Sts_IP"] and not out["Sts_ER"]
    sent = len(motion_commands(b.rx()))
    b.until(lambda: b.get("R.Robot.Sts.PointsInBuffer") == 0, 30000, "sent points done")
    assert len(motion_commands(b.rx())) == sent <= 5


def test_stop_ends_the_path_with_1007(bench):
    b = bench()
    b.path([pnp_point(i) for i in range(3)])
    b.run("A", 0, 3)
    b.scan(200)
    b.set("R.Stop", True)
    out = until_end(b, max_scans=200)
    assert out["Sts_ER"] and out["Sts_ERR"] == 1007 and out["Sts_EXERR"] == 0
    assert script_of(b.rx()[-1])[1] == "StopAndClearBuffer(0)"
    snap = b.robot().snapshot()
    assert not snap["moving"] and snap["queue_length"] == 0


def test_connection_lost_mid_path(bench):
    b = bench(faults=["drop:400"])
    b.path([pnp_point(i) for i in range(3)])
    b.run("A", 0, 3)
    out = until_end(b)
    assert out["Sts_ER"] and out["Sts_ERR"] == 1002 and out["Sts_EXERR"] == 1     # last active point
    assert b.get("R.Robot.Sts.Faulted") and not b.get("R.Robot.Sts.Running")
    for frame in b.rx():                          # every frame the PLC sent is whole (no half motion)
        assert frame.endswith(b"\r\n") and frame[-5:-4] == b"*"


def test_refused_target_is_1044_and_faults_the_handler(bench):
    b = bench()
    b.path([pnp_point(0), cartesian((2000.0, 0.0, 300.0, 180, 0, 90))])
    b.run("A", 0, 2)
    out = until_end(b)
    assert out["Sts_ERR"] == 1044 and out["Sts_EXERR"] == 1
    assert any(f.startswith(b"$TMSCT") and b",ERROR;" in f for f in b.tx())     # the robot refused it
    assert b.get("R.Robot.Sts.Faulted")
    b.set("R.AEnable", False)
    b.scan(2)
    b.run("A", 0, 1)
    b.scan(1)
    assert b.get("R.A.Sts_ERR") == 1002            # faulted handler
    b.set("R.AEnable", False)
    b.set("R.Reset", True)
    b.scan(2)
    b.run("A", 0, 1)
    assert until_end(b)["Sts_PC"]                  # after Cmd_Reset


def test_robot_not_in_external_mode_is_1006(bench):
    """The TM flow leaves its Listen node on a data time-out (Fail path, tm_protocol.md 1.6): the next
    point gets CPERR F1 (1002 for that path), and a new path then 1006 at once."""
    b = bench(settings=emulator.EmulatorSettings(data_timeout_ms=300, after_exit="stay"))
    b.scan(400)
    b.path([pnp_point(0)])
    b.run("A", 0, 1)
    out = until_end(b, max_scans=500)
    assert out["Sts_ERR"] == 1002 and tm_frame("CPERR", "F1") in b.tx()
    b.set("R.AEnable", False)
    b.set("R.Reset", True)
    b.scan(2)
    b.run("A", 0, 1)
    b.scan(1)
    assert b.get("R.A.Sts_ER") and b.get("R.A.Sts_ERR") == 1006


def test_handler_not_running_is_1001(bench):
    b = bench(enable_handler=False)
    b.path([pnp_point(0)])
    b.run("A", 0, 1)
    b.scan(1)
    assert b.get("R.A.Sts_ERR") == 1001 and b.rx() == []


def test_registry_full_is_1000(bench):
    b = bench()
    for i in range(8):
        b.set(f"R.Robot.Registry[{i}].MtdID", 1000 + i)
    b.path([pnp_point(0)])
    b.run("A", 0, 1)
    b.scan(1)
    assert b.get("R.A.Sts_ERR") == 1000


def test_tracking_requested_is_1003(bench):
    b = bench()
    b.path([pnp_point(0)])
    b.set("R.ATracking1", True)
    b.run("A", 0, 1)
    b.scan(1)
    assert b.get("R.A.Sts_ERR") == 1003 and b.get("R.A.Sts_EXERR") == 0 and len(b.rx()) == 1


def bad(**changes):
    p = pnp_point(0)
    p.update(changes)
    return p


@pytest.mark.parametrize(("start", "number", "points", "code", "exerr"), [
    (-1, 1, None, 1012, 0),                                     # EXERR >= 0 (seed 2.3): 0 for 1012
    (20, 1, None, 1012, 0),
    (-2147483648, 1, None, 1012, 0),
    (2147483647, 1, None, 1012, 0),
    (0, 0, None, 1010, 0),                                      # empty path; EXERR: the start index
    (0, -3, None, 1010, 0),
    (15, 6, None, 1010, 15),                                    # longer than the array
    (0, 21, None, 1010, 0),
    (5, 2147483647, None, 1010, 5),                             # issue 31 item 1: 5 + max wrapped, then faulted
    (19, 2147483647, None, 1010, 19),
    (0, -2147483648, None, 1010, 0),
    (0, 1, [bad(Speed=0.0)], 1013, 0),
    (0, 1, [bad(Deceleration=-1.0)], 1013, 0),
    (0, 1, [bad(AccelerationJerk=101.0)], 1014, 0),
    (0, 1, [cartesian((417.5, -122.3, 300.0, 180, 0, 90), interpolation=1) | {"OrientationSpeed": 0.0}], 1015, 0),
    (0, 2, [pnp_point(0), bad(MoveType=2)], 1017, 1),
    (0, 2, [pnp_point(0), bad(TargetPointType=2)], 1018, 1),    # hybrid: not possible on a TM
    (0, 1, [bad(InterpolationType=2)], 1020, 0),                # CP-W
    (0, 1, [bad(InterpolationType=3)], 1020, 0),                # CP-C
    (0, 1, [joints((10, 0, 0, 0, 0, 0), move_type=1, interpolation=1) | {"OrientationSpeed": 1.0,
            "OrientationAcceleration": 1.0, "OrientationDeceleration": 1.0}], 1020, 0),
    (0, 1, [bad(CommandTolerance=-1.0)], 1022, 0),
    (0, 1, [bad(CommandTolerance=101.0)], 1023, 0),
    (0, 1, [bad(TerminationType=3)], 1024, 0),
    (0, 1, [bad(ProfileType=4)], 1025, 0),
    (0, 1, [bad(RobotConfiguration=16)], 1026, 0),
    (0, 1, [bad(**{"Pose.FrameType": 1})], 1027, 0),
    (0, 1, [bad(**{"Pose.RefFrameType": 3})], 1028, 0),
    (0, 1, [bad(**{"Pose.FrameType": 3, "Pose.ID": 16})], 1029, 0),
    (0, 1, [bad(**{"Pose.RefFrameType": 4, "Pose.RefFrameID": -1})], 1030, 0),
    (0, 1, [bad(**{"Pose.FrameType": 3, "Pose.ID": 4})], 1031, 0),
    (0, 1, [bad(**{"Pose.RefFrameType": 4, "Pose.RefFrameID": 5})], 1032, 0),
    (0, 1, [joints((10, 0, 170, 0, 90, 0))], 1033, 0),
    (0, 1, [bad(MoveType=1, **{"Pose.FrameType": 3, "Pose.ID": 0})], 1031, 0),
    (0, 1, [bad(**{"Pose.X": math.nan})], 1037, 0),
    (0, 1, [cartesian((417.5, -122.3, 300.0, 180, 0, 90), interpolation=1, config=1)], 1048, 0),
    (0, 1, [joints((0, 0, 90, 0, 90, 0)) | {"Joints[6]": 5.0}], 1058, 0),
])
def test_error_codes(bench, start, number, points, code, exerr):
    b = bench()
    b.path(points or [pnp_point(0)], start=start if 0 <= start < 20 else 0)
    b.run("A", start, number)
    b.scan(1)
    out = b.outputs()
    assert out["Sts_ER"] and out["Sts_ERR"] == code and out["Sts_EXERR"] == exerr
    assert not out["Sts_IP"] and not out["Sts_PC"]
    b.scan(20)
    assert len(b.rx()) == 1                                    # nothing of an invalid path was sent


def test_incremental_move_wrt_tool_is_1035(bench):
    b = bench()
    b.set("R.Robot.Cfg.ToolConfigured[1]", True)
    b.path([bad(MoveType=1, **{"Pose.FrameType": 3, "Pose.ID": 1})])
    b.run("A", 0, 1)
    b.scan(1)
    assert b.get("R.A.Sts_ERR") == 1035


def test_start_and_number_are_latched_on_the_rising_edge(bench):
    """Issue 31 item 2: changing Cfg_StartIndex / Cfg_NumberOfMoves while In Process faulted the
    controller (start 18: index 23 out of 0..19) or loaded points never validated; they are latched
    when validated, so the path runs as it was started and the change waits for the next rising edge."""
    b = bench()
    b.path([pnp_point(i) for i in range(6)])
    b.path([cartesian((2000.0, 0.0, 300.0, 180, 0, 90)), bad(Speed=0.0)], start=18)   # unreachable, invalid
    b.run("A", 0, 6)
    b.scan(5)
    b.set("R.AStart", 18)
    b.scan(3)
    b.set("R.ANumber", 2147483647)
    end = until_end(b)
    assert end["Sts_PC"] and not end["Sts_ER"]
    assert [args[1:4] for _, args in motion_commands(b.rx())] == [list(t[:3]) for t in PNP_TARGETS]
    b.set("R.AEnable", False)
    b.scan(1)
    b.set("R.AEnable", True)                        # the new values count from this rising edge
    b.scan(1)
    assert b.get("R.A.Sts_ERR") == 1010 and b.get("R.A.Sts_EXERR") == 18


def test_chained_instance_keeps_the_dynamics_and_blends_across_the_calls(bench):
    """Seed 1.3 / 1.3.8 (issue 31 items 3 and 6): a second LoadPath started while the first one's
    points are in the buffer continues the path: zero dynamics on its first point keep the last
    values (no 1013), and a blended last point of the first call blends into the second call's."""
    b = bench()
    b.path([pnp_point(0, move_id=1), cartesian((400.0, -150.0, 250.0, 180, 0, 90), move_id=2, termination=6,
                                              tolerance=40.0, speed=36.0, accel=180.0)])
    second = cartesian((400.0, -100.0, 250.0, 180, 0, 90), move_id=3, speed=0.0, accel=0.0)
    second["AccelerationJerk"] = second["DecelerationJerk"] = 0.0
    b.path([second], start=5)
    b.watch = {"Active": "R.Robot.Sts.ActiveMoveID", "Blending": "R.Robot.Sts.BlendingMoveID"}
    b.run("A", 0, 2)
    b.scan(1)
    b.run("B", 5, 1)
    b.scan(1)
    assert b.get("R.B.Sts_IP") and not b.get("R.B.Sts_ER")
    until_end(b, "A")
    assert until_end(b, "B")["Sts_PC"]
    commands = motion_commands(b.rx())
    assert commands[1][1][-2:] == [40.0, True]                 # point 2 blends ...
    assert commands[2][1][7:9] == [20.0, 200.0]                # ... into B's point with A's last dynamics
    assert (2, 3) in {(s["Active"], s["Blending"]) for s in b.samples}


def test_a_new_path_with_zero_dynamics_is_still_1013(bench):
    b = bench()
    b.path([pnp_point(0)])
    b.run("A", 0, 1)
    until_end(b)
    b.path([bad(Speed=0.0)], start=3)
    b.run("B", 3, 1)                                          # the buffer is empty: a new path
    b.scan(1)
    assert b.get("R.B.Sts_ERR") == 1013 and b.get("R.B.Sts_EXERR") == 3


def test_tracking0_requested_is_1003(bench):
    b = bench()
    b.path([pnp_point(0)], start=4)
    b.set("R.ATracking0", True)
    b.run("A", 4, 1)
    b.scan(1)
    assert b.get("R.A.Sts_ERR") == 1003 and b.get("R.A.Sts_EXERR") == 4 and len(b.rx()) == 1


def test_active_status_members_follow_the_executing_point(bench):
    b = bench()
    b.set_many("R.Robot.Cfg.ToolFrames[2]", {"Z": 100.0})
    b.set("R.Robot.Cfg.ToolConfigured[2]", True)
    b.set_many("R.Robot.Cfg.UserFrames[3]", {"X": 10.0})
    b.set("R.Robot.Cfg.UserConfigured[3]", True)
    b.path([pnp_point(0, move_id=11),
            cartesian((400.0, -150.0, 150.0, 180, 0, 90), move_id=12, interpolation=1, frame_type=3, tool_id=2,
                      ref_type=4, ref_id=3, speed=200.0, accel=1000.0)])
    b.watch = {k: f"R.Robot.Sts.Active{k}" for k in ("MoveID", "Interpolation", "Type", "TypeID", "RefFrameType",
                                                      "RefFrameID")}
    b.run("A", 0, 2)
    assert until_end(b)["Sts_PC"]
    seen = {tuple(s[k] for k in ("MoveID", "Interpolation", "Type", "TypeID", "RefFrameType", "RefFrameID"))
            for s in b.samples if s["MoveID"]}
    assert seen == {(11, 0, 2, 0, 1, 0), (12, 1, 3, 2, 4, 3)}


def test_handler_stopping_is_1003_for_a_new_path(bench):
    """Seed 2.3 1003: the handler is not Available while its stop is going out."""
    b = bench()
    b.path([pnp_point(i) for i in range(3)])
    b.run("A", 0, 3)
    b.scan(100)
    b.set("R.Stop", True)
    b.scan(1)                                                 # the stop is requested, not yet answered
    assert not b.get("R.Robot.Sts.Available") and b.get("R.Robot.Sts.Running")
    b.run("B", 5, 1)
    b.scan(1)
    assert b.get("R.B.Sts_ERR") == 1003 and b.get("R.B.Sts_EXERR") == 0


# ------------------------------------------------------------------------- emulator choices (docs/emulator.md)


@pytest.mark.parametrize("applies", [True, False])
def test_after_a_stop_the_next_path_runs_in_its_own_frame_whatever_the_robot_kept(bench, applies):
    """A stop drops a point whose ChangeBase was queued; whether the robot keeps that base is the
    emulator switch stop_applies_queued_frames. The handler sends tool and base again after a stop,
    so the next path ends at the same place under both choices."""
    b = bench(settings=emulator.EmulatorSettings(stop_applies_queued_frames=applies))
    b.set_many("R.Robot.Cfg.UserFrames[3]", {"X": 10.0, "Y": 20.0})
    b.set("R.Robot.Cfg.UserConfigured[3]", True)
    b.path([pnp_point(0), cartesian((400.0, -150.0, 250.0, 180, 0, 90), ref_type=4, ref_id=3, speed=36.0,
                                    accel=180.0)])
    b.run("A", 0, 2)
    b.scan(60)                                          # both points on the robot, the first one moving
    b.set("R.Stop", True)
    assert until_end(b, max_scans=300)["Sts_ERR"] == 1007
    b.set("R.Stop", False)
    b.set("R.AEnable", False)
    b.scan(2)
    # the same user frame as the dropped point: the handler may not assume the robot has it
    b.path([cartesian(PNP_TARGETS[3], ref_type=4, ref_id=3)], start=5)
    b.run("B", 5, 1)
    assert until_end(b, "B")["Sts_PC"]
    assert "ChangeBase(10.00,20.00,0.00,0.00,0.00,0.00)" in script_of(b.rx()[-1])[1]
    x, y, z = PNP_TARGETS[3][:3]
    assert list(matrix_to_pose(b.robot().executor.current_tcp()))[:3] == pytest.approx([x + 10.0, y + 20.0, z],
                                                                                       abs=0.05)


@pytest.mark.parametrize("reject", [False, True])
def test_a_zero_length_point_completes_or_is_a_refused_target(bench, reject):
    """A point at the pose the robot is at: the emulator switch reject_zero_length_motion decides
    whether the TM runs it (done at once) or refuses it (1044, as any refused target)."""
    b = bench(settings=emulator.EmulatorSettings(reject_zero_length_motion=reject))
    b.path([pnp_point(0), pnp_point(0, move_id=7)])
    b.run("A", 0, 2)
    out = until_end(b)
    if reject:
        assert out["Sts_ER"] and out["Sts_ERR"] == 1044 and out["Sts_EXERR"] == 1
    else:
        assert out["Sts_PC"] and not out["Sts_ER"]


def test_status_estimates_from_polled_poses(bench):
    """Issue 31 item 3: with Cfg.StatusPollPeriod the handler polls the TCP (ListenSend 92,
    Robot[0].CoordRobot) and estimates ActiveMovePerc and the linear/angular velocity and
    acceleration; without it (the default) nothing is polled and they stay 0."""
    b = bench()
    b.set("R.Robot.Cfg.StatusPollPeriod", 50_000_000)            # 50 ms
    b.path([cartesian((400.0, -150.0, 300.0, 180, 0, 90), move_id=1, interpolation=1, speed=100.0, accel=500.0),
            cartesian((400.0, -150.0, 100.0, 180, 0, 90), move_id=2, interpolation=1, speed=100.0, accel=500.0)])
    b.watch = {"Perc": "R.Robot.Sts.ActiveMovePerc", "V": "R.Robot.Sts.LinearVelocity", "ID": "R.Robot.Sts.ActiveMoveID",
               "W": "R.Robot.Sts.AngularVelocity", "A": "R.Robot.Sts.LinearAccleration"}
    b.run("A", 0, 2)
    assert until_end(b)["Sts_PC"]
    assert any(b"ListenSend(92,GetString(Robot[0].CoordRobot))" in f for f in b.rx())
    second = [s for s in b.samples if s["ID"] == 2]
    percs = [s["Perc"] for s in second]
    assert percs == sorted(percs) and 40.0 < max(percs) <= 100.0          # rises along the 200 mm line
    assert max(s["V"] for s in second) == pytest.approx(100.0, rel=0.1)  # the commanded 100 mm/s
    assert max(abs(s["W"]) for s in second) < 1.0                        # the orientation does not change
    assert any(s["A"] > 0 for s in second) and any(s["A"] < 0 for s in second)


def test_no_status_polling_by_default(bench):
    b = bench()
    b.path([pnp_point(0)])
    b.run("A", 0, 1)
    until_end(b)
    assert not any(b"ListenSend" in f for f in b.rx())
    assert b.get("R.Robot.Sts.LinearVelocity") == 0.0 and b.get("R.Robot.Sts.ActiveMovePerc") == 0.0
