"""The mxAutomation-style motion and read FBs on a TM (st_src/kuka) against the emulated robot in
lockstep: the TM script of each FB (A/B/C converted, APO and COORDSYS mapped), Busy/Active/Done/
Aborted, BUFFERED and ABORTING, reading the actual position, every error code, and the robot's own
answers (refusal, lost connection)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emulator.motion import euler_to_matrix
from kuka_harness import KukaBench
from robotlibs_helpers import motion_commands, script_of


@pytest.fixture
def bench():
    made = []

    def make(**kw):
        b = KukaBench(**kw)
        made.append(b)
        return b
    yield make
    for b in made:
        b.close()


def sent_scripts(b) -> list[str]:
    return [script_of(f)[1] for f in b.rx() if f.startswith(b"$TMSCT") and b"ListenSend" not in f]


def kuka_matrix(a, b, c):
    def rot(axis, deg):
        c_, s_ = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        m = {"x": [[1, 0, 0], [0, c_, -s_], [0, s_, c_]], "y": [[c_, 0, s_], [0, 1, 0], [-s_, 0, c_]],
             "z": [[c_, -s_, 0], [s_, c_, 0], [0, 0, 1]]}[axis]
        return np.array(m)
    return rot("z", a) @ rot("y", b) @ rot("x", c)


def test_ptp_to_e6pos_with_abc(bench):
    b = bench()
    b.pos("K.PtpPosition", 417.5, -122.3, 330.0, 80.0, 10.0, 170.0)
    b.set("K.PtpExecute", True)
    out = b.finish("Ptp")
    assert out["Done"] and not out["Error"]
    assert sent_scripts(b)[0] == 'PTP("CPP",417.50,-122.30,330.00,170.00,10.00,80.00,50,200,0,false)\r\nQueueTag(1,0)'
    # the robot's TCP orientation is the KUKA orientation
    pose = b.robot().snapshot()["pose"]
    assert np.allclose(euler_to_matrix(*pose[3:]), kuka_matrix(80.0, 10.0, 170.0), atol=1e-4)


def test_active_while_executing_and_buffered_queueing(bench):
    b = bench()
    b.pos("K.PtpPosition", 417.5, -122.3, 260.0, 90.0, 0.0, 180.0)
    b.pos("K.Ptp2Position", 437.5, -122.3, 260.0, 90.0, 0.0, 180.0)
    b.watch = {"A1": "K.Ptp.Active", "A2": "K.Ptp2.Active", "D1": "K.Ptp.Done", "D2": "K.Ptp2.Done"}
    b.set("K.PtpExecute", True)
    b.set("K.Ptp2Execute", True)                  # BUFFERED: queued behind the first
    b.finish("Ptp2")
    states = [(s["A1"], s["A2"]) for s in b.samples]
    assert (True, False) in states and (False, True) in states and (True, True) not in states
    first_done = next(i for i, s in enumerate(b.samples) if s["D1"])
    assert b.samples[first_done]["A2"] or b.samples[first_done + 1]["A2"]
    assert b.pose()[:3] == pytest.approx([437.5, -122.3, 260.0], abs=0.02)


def test_aborting_drops_the_running_motion(bench):
    b = bench()
    b.pos("K.PtpPosition", 417.5, -122.3, 200.0, 90.0, 0.0, 180.0)
    b.pos("K.Ptp2Position", 437.5, -122.3, 330.0, 90.0, 0.0, 180.0)
    b.set("K.PtpVelocity", 10)
    b.set("K.PtpExecute", True)
    b.scan(300)
    b.set("K.Ptp2BufferMode", 1)
    b.set("K.Ptp2Execute", True)
    out = b.finish("Ptp")
    assert out["Aborted"] and not out["Error"] and not out["Done"]
    assert b.finish("Ptp2")["Done"]
    assert sent_scripts(b)[1].startswith("StopAndClearBuffer()\r\nPTP(")
    assert b.pose()[:3] == pytest.approx([437.5, -122.3, 330.0], abs=0.02)


def test_linear_move_with_distance_and_velocity_contouring(bench):
    b = bench()
    b.pos("K.LinPosition", 417.5, -122.3, 300.0, 90.0, 0.0, 180.0)
    b.set_many("K.LinApo", {"CP_MODE": 1, "CDIS": 12.5})
    b.set("K.LinExecute", True)
    assert b.finish("Lin")["Done"]
    b.set("K.LinExecute", False)
    b.scan(2)
    b.pos("K.LinPosition", 417.5, -122.3, 280.0, 90.0, 0.0, 180.0)
    b.set_many("K.LinApo", {"CP_MODE": 3, "CVEL": 40})
    b.set("K.LinExecute", True)
    assert b.finish("Lin")["Done"]
    first, second = sent_scripts(b)
    assert first.split("\r\n")[0] == 'Line("CPR",417.50,-122.30,300.00,180.00,0.00,90.00,20,200,12.50,true)'
    assert second.split("\r\n")[0] == 'Line("CPP",417.50,-122.30,280.00,180.00,0.00,90.00,20,200,40,true)'


def test_axis_move_and_contouring_ptp(bench):
    b = bench()
    b.set_many("K.AxisPosition", {"A1": 10.0, "A2": 5.0, "A3": 80.0, "A4": 0.0, "A5": 95.0, "A6": 0.0})
    b.set_many("K.AxisApo", {"PTP_MODE": 1, "CPTP": 30})
    b.set("K.AxisExecute", True)
    assert b.finish("Axis")["Done"]
    assert sent_scripts(b)[0].split("\r\n")[0] == 'PTP("JPP",10.00,5.00,80.00,0.00,95.00,0.00,50,200,30,true)'
    b.scan(500)
    assert b.robot().snapshot()["joints"] == pytest.approx([10.0, 5.0, 80.0, 0.0, 95.0, 0.0], abs=0.01)


def test_coordsys_tool_and_base_are_sent_when_they_change(bench):
    b = bench()
    b.set_many("K.Group.Connect", {})
    b.set_many("KRC_AXISGROUPREFARR[1].TOOL_DATA[3]", {"Z": 120.0, "A": 90.0})
    b.set_many("KRC_AXISGROUPREFARR[1].BASE_DATA[2]", {"X": 50.0, "C": 180.0})
    b.set_many("K.PtpCoordSys", {"Tool": 3, "Base": 2})
    b.pos("K.PtpPosition", 367.5, 122.3, -200.0, 0.0, 0.0, 0.0)
    b.set("K.PtpExecute", True)
    assert b.finish("Ptp")["Done"]
    b.set("K.PtpExecute", False)
    b.scan(2)
    b.pos("K.PtpPosition", 367.5, 122.3, -220.0, 0.0, 0.0, 0.0)
    b.set("K.PtpExecute", True)
    assert b.finish("Ptp")["Done"]
    first, second = sent_scripts(b)
    assert first.split("\r\n")[:2] == ["ChangeTCP(0.00,0.00,120.00,0.00,0.00,90.00)",
                                      "ChangeBase(50.00,0.00,0.00,180.00,0.00,0.00)"]
    assert second.startswith("PTP(")                      # same tool and base: not sent again
    b.set("K.PtpExecute", False)
    b.set_many("K.PtpCoordSys", {"Tool": 0, "Base": 0})
    b.scan(2)
    b.set("K.PtpExecute", True)
    b.finish("Ptp")
    assert sent_scripts(b)[2].split("\r\n")[:2] == ['ChangeTCP("NOTOOL")', 'ChangeBase("RobotBase")']


def test_velocity_zero_keeps_the_last_one(bench):
    b = bench()
    b.set("K.PtpVelocity", 30)
    b.pos("K.PtpPosition", 417.5, -122.3, 340.0, 90.0, 0.0, 180.0)
    b.set("K.PtpExecute", True)
    b.finish("Ptp")
    b.set("K.PtpExecute", False)
    b.set("K.PtpVelocity", 0)
    b.set("K.PtpAcceleration", 0)
    b.scan(2)
    b.set("K.PtpExecute", True)
    b.finish("Ptp")
    assert [args[7:9] for _, args in motion_commands(b.rx())] == [[30.0, 200.0], [30.0, 200.0]]


def test_read_actual_position(bench):
    b = bench()
    b.until(lambda: b.get("K.Read.Valid") and b.get("K.ReadAxis.Valid"), 1000, "valid")
    assert [b.get(f"K.Read.Position.{k}") for k in "XYZABC"] == pytest.approx([417.5, -122.3, 360.9, 90.0, 0.0, 180.0],
                                                                             abs=1e-3)
    assert [b.get(f"K.ReadAxis.AxisPosition.A{i}") for i in range(1, 7)] == pytest.approx([0, 0, 90, 0, 90, 0], abs=1e-3)
    b.pos("K.PtpPosition", 400.0, -100.0, 300.0, 60.0, 5.0, 175.0)
    b.set("K.PtpExecute", True)
    b.finish("Ptp")
    b.scan(450)
    got = [b.get(f"K.Read.Position.{k}") for k in "XYZABC"]
    assert got[:3] == pytest.approx([400.0, -100.0, 300.0], abs=0.02)
    assert np.allclose(kuka_matrix(*got[3:]), kuka_matrix(60.0, 5.0, 175.0), atol=1e-4)
    listen = [s for s in (script_of(f)[1] for f in b.rx() if f.startswith(b"$TMSCT")) if "ListenSend" in s]
    assert set(listen) == {"ListenSend(90,GetString(Robot[0].CoordBase))", "ListenSend(91,GetString(Robot[0].Joint))"}


@pytest.mark.parametrize(("inputs", "code"), [
    ({"K.PtpGroup": 6}, 501),
    ({"K.PtpVelocity": 101}, 510),
    ({"K.PtpAcceleration": -1}, 511),
    ({"K.PtpBufferMode": 0}, 512),
    ({"K.PtpCoordSys.Tool": 17}, 520),
    ({"K.PtpCoordSys.Base": -2}, 521),
    ({"K.PtpCoordSys.IPO_MODE": 1}, 522),                 # stationary tool
    ({"K.PtpApo.PTP_MODE": 2}, 530),                      # PTP-CP contouring
    ({"K.PtpApo.PTP_MODE": 1, "K.PtpApo.CPTP": 0}, 532),
    ({"K.PtpPosition.E1": 5.0}, 540),                     # additional axis
])
def test_ptp_errors(bench, inputs, code):
    b = bench()
    b.pos("K.PtpPosition", 417.5, -122.3, 330.0, 90.0, 0.0, 180.0)
    for key, value in inputs.items():
        b.set(key, value)
    b.set("K.PtpExecute", True)
    out = b.finish("Ptp", 10)
    assert out["Error"] and out["ErrorID"] == code
    assert sent_scripts(b) == []


@pytest.mark.parametrize(("inputs", "code"), [
    ({"K.LinApo.CP_MODE": 2}, 531),                       # orientation contouring
    ({"K.LinApo.CP_MODE": 4}, 531),
    ({"K.LinApo.CP_MODE": 1, "K.LinApo.CDIS": -1.0}, 532),
    ({"K.LinApo.CP_MODE": 3, "K.LinApo.CVEL": 101}, 532),
    ({"K.LinOriType": 1}, 541),                           # CONSTANT orientation
    ({"K.LinOriType": 2}, 541),                           # JOINT
])
def test_linear_errors(bench, inputs, code):
    b = bench()
    b.pos("K.LinPosition", 417.5, -122.3, 330.0, 90.0, 0.0, 180.0)
    for key, value in inputs.items():
        b.set(key, value)
    b.set("K.LinExecute", True)
    out = b.finish("Lin", 10)
    assert out["Error"] and out["ErrorID"] == code


def test_axis_errors(bench):
    b = bench()
    b.set_many("K.AxisPosition", {"A3": 90.0, "A5": 90.0, "E2": 1.0})
    b.set("K.AxisExecute", True)
    assert b.finish("Axis", 10)["ErrorID"] == 540


def test_group_not_connected_and_group_index(bench):
    b = bench(connect=False)
    b.set("K.PtpExecute", True)
    assert b.finish("Ptp", 10)["ErrorID"] == 502
    b.set("K.GroupIdx", 0)
    b.set("K.GroupEnable", True)
    b.scan(1)
    assert b.get("K.Group.Error") and b.get("K.Group.ErrorID") == 501


def test_robot_refusal_and_lost_connection(bench):
    b = bench()
    b.pos("K.PtpPosition", 2000.0, 0.0, 300.0, 90.0, 0.0, 180.0)      # out of reach
    b.set("K.PtpExecute", True)
    assert b.finish("Ptp")["ErrorID"] == 10000 + 0x80
    b.set("K.PtpExecute", False)
    b.scan(2)
    b.transport.inject_fault("drop:100")
    b.pos("K.PtpPosition", 417.5, -122.3, 250.0, 90.0, 0.0, 180.0)
    b.set("K.PtpExecute", True)
    assert b.finish("Ptp")["ErrorID"] == 10000 + 0x99
    b.scan(5)
    assert not b.get("K.Group.Valid") and b.get("K.Group.ErrorID") == 0x90


# ------------------------------------------------------------------------- the seed STRUCTs, element by element (issue 31 item 5)


@pytest.mark.parametrize(("status", "config"), [
    (0, None),                          # not given: the TM takes the nearest configuration
    (1, [1.0, 2.0, 4.0]),               # overhead -> Lefty
    (2, [0.0, 3.0, 4.0]),               # A3 bit -> Below
    (4, [0.0, 2.0, 5.0]),               # A5 <= 0 -> Flip
    (7, [1.0, 3.0, 5.0]),
    (8 + 2, [0.0, 3.0, 4.0]),           # bit 3 (unused by KUKA) ignored
    (16 + 4, [0.0, 2.0, 5.0]),          # bit 4 (absolutely accurate) ignored
])
def test_e6pos_status_is_the_tm_pose_configuration(bench, status, config):
    b = bench()
    b.pos("K.PtpPosition", 417.5, -122.3, 330.0, 90.0, 0.0, 180.0)
    b.set("K.PtpPosition.S", status)
    b.set("K.PtpPosition.T", 35)                              # Turn: no TM counterpart, ignored
    b.set("K.PtpExecute", True)
    out = b.finish("Ptp")
    assert out["Done"] and not out["Error"]                   # the emulator accepts the configuration
    name, args = motion_commands(b.rx())[0]
    assert name == "PTP" and (args[11:] if config else len(args)) == (config if config else 11)


@pytest.mark.parametrize("status", [-1, -32768])
def test_e6pos_status_negative_is_542(bench, status):
    b = bench()
    b.pos("K.PtpPosition", 417.5, -122.3, 330.0, 90.0, 0.0, 180.0)
    b.set("K.PtpPosition.S", status)
    b.set("K.PtpExecute", True)
    out = b.finish("Ptp", 10)
    assert out["Error"] and out["ErrorID"] == 542 and sent_scripts(b) == []


def test_linear_target_ignores_status_and_turn(bench):
    b = bench()
    b.pos("K.LinPosition", 417.5, -122.3, 300.0, 90.0, 0.0, 180.0)
    b.set_many("K.LinPosition", {"S": 7, "T": 63})
    b.set("K.LinExecute", True)
    assert b.finish("Lin")["Done"]
    assert len(motion_commands(b.rx())[0][1]) == 11


@pytest.mark.parametrize("element", ["E1", "E2", "E3", "E4", "E5", "E6"])
@pytest.mark.parametrize("fb", ["Ptp", "Lin"])
def test_every_additional_axis_of_e6pos_is_540(bench, fb, element):
    b = bench()
    b.pos(f"K.{fb}Position", 417.5, -122.3, 330.0, 90.0, 0.0, 180.0)
    b.set(f"K.{fb}Position.{element}", -0.5)
    b.set(f"K.{fb}Execute", True)
    out = b.finish(fb, 10)
    assert out["Error"] and out["ErrorID"] == 540 and sent_scripts(b) == []


@pytest.mark.parametrize("element", ["E1", "E2", "E3", "E4", "E5", "E6"])
def test_every_additional_axis_of_e6axis_is_540(bench, element):
    b = bench()
    b.set_many("K.AxisPosition", {"A3": 90.0, "A5": 90.0, element: 2.0})
    b.set("K.AxisExecute", True)
    out = b.finish("Axis", 10)
    assert out["Error"] and out["ErrorID"] == 540 and sent_scripts(b) == []


@pytest.mark.parametrize(("cp_mode", "outcome"), [(0, "Done"), (1, "Done"), (2, 531), (3, "Done")])
def test_apo_cori_is_only_read_by_orientation_contouring(bench, cp_mode, outcome):
    """APO.CORI (orientation parameter) belongs to CP_MODE 2, which a TM Line cannot do (531); with any
    other mode it is not used, whatever its value."""
    b = bench()
    b.pos("K.LinPosition", 417.5, -122.3, 300.0, 90.0, 0.0, 180.0)
    b.set_many("K.LinApo", {"CP_MODE": cp_mode, "CORI": 45.0, "CDIS": 5.0, "CVEL": 50})
    b.set("K.LinExecute", True)
    out = b.finish("Lin")
    if outcome == "Done":
        assert out["Done"] and "45" not in sent_scripts(b)[0].split("\r\n")[0].split(",")[-2]
    else:
        assert out["Error"] and out["ErrorID"] == outcome
