"""CBT_Commands V2 FBs against the emulated TM robot in lockstep: frames byte for byte (computed from
tm_protocol.md), CommandID and QueueTag managed per connection, every parameter check, the new
Listen Node functions (stop and clear, digital output, queue-tag status, leaving the node)."""

from __future__ import annotations

import pytest

from robotlibs_helpers import script_of, tm_frame
from v2_harness import V2Bench, move_params, pose_text

import emulator

HOME_LISTEN = b"$TMSTA,2,00,*41\r\n"


@pytest.fixture
def bench():
    made = []

    def make(*instances, **kw):
        b = V2Bench(*instances, **kw)
        made.append(b)
        return b
    yield make
    for b in made:
        b.close()


# ------------------------------------------------------------------------- connection


def test_connect_sends_the_status_query_and_is_connected(bench):
    b = bench()
    assert b.rx() == [HOME_LISTEN]
    assert b.tx() == [tm_frame("TMSTA", "00,true,Listen1")]
    assert b.get("T.Conn.Busy") and b.get("T.Conn.Connected") and b.get("T.Cobot.InListenNode")
    assert b.get("T.Cobot.Decimals") == 2


@pytest.mark.parametrize(("inputs", "code", "text"), [
    ({"TimeOut": 9}, 0x15, "Timeout range: 10~300 seconds"),
    ({"TimeOut": 301}, 0x15, "Timeout range: 10~300 seconds"),
    ({"Port": 0}, 0x16, "Port range: 1~65535"),
    ({"Decimals": 5}, 0x17, "Decimals range: 0~4"),
])
def test_connect_input_ranges(bench, inputs, code, text):
    b = bench(connect=False)
    for key, value in inputs.items():
        b.set(f"T.{key}", value)
    b.set("T.ConnExecute", True)
    b.until(lambda: b.get("T.Conn.Error"), 100)
    assert b.get("T.Conn.ErrorID") == code and b.get("T.Conn.ErrorDescrip") == text
    assert b.rx() == []                                   # nothing was opened


def test_connect_to_a_robot_not_in_the_listen_node_closes_the_socket(bench):
    b = bench(connect=False, settings=emulator.EmulatorSettings(start_in_node=False))
    b.set("T.ConnExecute", True)
    b.until(lambda: b.get("T.Conn.Error"), 200)
    assert b.get("T.Conn.ErrorID") == 0x70
    assert b.tx() == [tm_frame("TMSTA", "00,false,")]
    b.scan(5)
    assert b.robot().connections == []                    # V1 leaves it open (sysmac.md 8.11)


def test_connect_refused(bench):
    b = bench(connect=False, faults=["refuse"])
    b.set("T.ConnExecute", True)
    b.until(lambda: b.get("T.Conn.Error"), 200)
    assert b.get("T.Conn.ErrorID") == 0x20 and not b.get("T.Cobot.Connected")


def test_execute_false_closes_and_reports_done_once(bench):
    b = bench()
    b.set("T.ConnExecute", False)
    b.until(lambda: b.get("T.Conn.Done"), 50)
    b.scan(1)
    assert not b.get("T.Conn.Done") and not b.get("T.Conn.Busy")
    assert not b.get("T.Cobot.Connected")
    b.scan(3)
    assert b.robot().connections == []


def test_connection_dropped_mid_motion_is_reported_and_clears_waiting_return(bench):
    b = bench("Abs", faults=["drop:50"])
    b.start("Abs", move_params(target=(417.5, -122.3, 250.0, 180.0, 0.0, 90.0)))
    end = b.finish("Abs")
    assert end["ErrorID"] == 0x99 and end["Error"]
    b.until(lambda: b.get("T.Conn.Error"), 10)           # after closing its socket
    assert b.get("T.Conn.ErrorID") == 0x90 and b.get("T.Conn.ErrorDescrip") == "Socket disconnected"
    assert not b.get("T.Cobot.WaitingReturn")             # V1 keeps it after a RST
    b.scan(3)
    assert b.robot().connections == []


# ------------------------------------------------------------------------- motions


def test_move_absolute_frame_reply_and_done(bench):
    b = bench("Abs")
    p = move_params()
    b.start("Abs", p)
    end = b.finish("Abs")
    assert end["Done"] and not end["Error"]
    expected = tm_frame("TMSCT", '1,PTP("CPP",417.50,-122.30,350.00,180.00,0.00,90.00,50,200,0,false)\r\nQueueTag(1,0)')
    assert b.rx()[1] == expected
    assert b.tx()[1:] == [tm_frame("TMSCT", "1,OK"), tm_frame("TMSTA", "01,01,true")]
    assert b.get("T.Abs.CmdID_Ack") == 1
    assert b.pose()[:3] == pytest.approx([417.5, -122.3, 350.0], abs=1e-3)
    assert not b.get("T.Cobot.WaitingReturn")


def test_command_ids_and_tags_are_managed_per_connection(bench):
    b = bench("Abs")
    sent = []
    for i in range(17):
        z = 350.0 - (i % 2) * 5
        b.start("Abs", move_params(target=(417.5, -122.3, z, 180.0, 0.0, 90.0), speed=100, accel=150))
        assert b.finish("Abs")["Done"]
        assert b.get("T.Abs.CmdID_Ack") == i + 1
        b.stop("Abs")
        b.scan(2)
    for frame in b.rx()[1:]:
        ident, script = script_of(frame)
        sent.append((int(ident), int(script.rsplit("QueueTag(", 1)[1].split(",")[0])))
    assert [i for i, _ in sent] == list(range(1, 18))
    assert [t for _, t in sent] == list(range(1, 16)) + [1, 2]    # QueueTag numbers 1..15, then again


def test_decimals_and_negative_zero(bench):
    b = bench("Abs", connect=False)
    b.set("T.Decimals", 3)
    b.connect()
    b.start("Abs", move_params(target=(417.4567, -122.3004, 350.0, 180.0, -0.0001, 90.0)))
    assert b.finish("Abs")["Done"]
    _, script = script_of(b.rx()[1])
    assert script.startswith('PTP("CPP",417.457,-122.300,350.000,180.000,0.000,90.000,50,200,0,false)')


def test_precise_positioning_is_sent_as_not_disable_precise(bench):
    b = bench("Abs")
    b.start("Abs", move_params(precise=False))
    assert b.finish("Abs")["Done"]
    assert script_of(b.rx()[1])[1].split("\r\n")[0].endswith(",0,true)")     # disablePrecise = TRUE


def test_robot_pose_enumeration(bench):
    b = bench("Abs")
    b.start("Abs", move_params(pose=("Lefty", "Below", "Flip")))
    b.finish("Abs")
    assert script_of(b.rx()[1])[1].split("\r\n")[0].endswith(",false,1,3,5)")


def test_line_with_blending_is_done_at_the_ok(bench):
    b = bench("Abs")
    b.start("Abs", move_params(movement="Line", fmt="CAR_Abs", speed=200, blend=20))
    end = b.finish("Abs")
    assert end["Done"]
    _, script = script_of(b.rx()[1])
    assert script == f'Line("CAR",{pose_text((417.5, -122.3, 350.0, 180.0, 0.0, 90.0))},200,200,20,false)'
    assert b.robot().snapshot()["moving"]                 # Done before the motion ended


@pytest.mark.parametrize(("inst", "params", "code"), [
    ("Abs", move_params(fmt="CAP_Abs"), 0x35),
    ("Abs", move_params(movement="Line", fmt="JPP_Abs"), 0x36),
    ("Abs", move_params(speed=0), 0x26),
    ("Abs", move_params(speed=101), 0x26),
    ("Abs", move_params(movement="Line", fmt="CPP_Abs", speed=101), 0x25),
    ("Abs", move_params(movement="Line", fmt="CAP_Abs", speed=4501), 0x25),
    ("Abs", move_params(accel=149), 0x27),
    ("Abs", move_params(accel=10000), 0x27),
    ("Abs", move_params(movement="Line", fmt="CPP_Abs", pose=("Righty", "Above", "NoFlip")), 0x29),
    ("Abs", move_params(blend=101), 0x2A),
    ("Abs", move_params(fmt="JPP_Abs", pose=("Righty", "Above", "NoFlip")), 0x2B),
])
def test_move_absolute_parameter_checks(bench, inst, params, code):
    b = bench(inst)
    b.start(inst, params)
    end = b.finish(inst, 100)
    assert end["Error"] and end["ErrorID"] == code
    assert len(b.rx()) == 1                               # nothing sent
    assert not b.get("T.Cobot.WaitingReturn")


def rel_params(movement="PTP", fmt="TPP_Rel", delta=(0.0, 0.0, 10.0, 0.0, 0.0, 0.0), speed=50, accel=200, blend=None):
    p = {"MovementCommand": movement, "DataFormat": fmt, "Speed": speed, "AccelTime": accel,
         "BlendingEnable": blend is not None, "BlendingValue": blend or 0, "PrecisePositioning": True}
    p.update({f"TargetPosition.{k}": v for k, v in zip(("X", "Y", "Z", "RX", "RY", "RZ"), delta)})
    return p


def test_move_relative_tool_frame(bench):
    b = bench("Rel")
    start = b.pose()
    b.start("Rel", rel_params())
    assert b.finish("Rel")["Done"]
    assert script_of(b.rx()[1])[1] == 'Move_PTP("TPP",0.00,0.00,10.00,0.00,0.00,0.00,50,200,0,false)\r\nQueueTag(1,0)'
    # tool Z points down (RX 180): +10 in the tool frame is -10 in the base
    assert b.pose()[2] == pytest.approx(start[2] - 10.0, abs=1e-3)


@pytest.mark.parametrize(("params", "code"), [
    (rel_params(fmt="CAP_Rel"), 0x30),
    (rel_params(movement="Line", fmt="JPP_Rel"), 0x31),
    (rel_params(speed=0), 0x26),
    (rel_params(movement="Line", fmt="TAP_Rel", speed=4501), 0x25),
    (rel_params(movement="Line", fmt="TPP_Rel", speed=101), 0x25),
    (rel_params(accel=100), 0x27),
    (rel_params(movement="Line", fmt="CPP_Rel", blend=101), 0x2A),
])
def test_move_relative_parameter_checks(bench, params, code):
    b = bench("Rel")
    b.start("Rel", params)
    end = b.finish("Rel", 100)
    assert end["Error"] and end["ErrorID"] == code and len(b.rx()) == 1


def circle_params(fmt="CAP_Circle", speed=200, accel=200, arc=0, blend=None):
    p = {"DataFormat": fmt, "Speed": speed, "AccelTime": accel, "ArcAngle": arc, "PrecisePositioning": True,
         "BlendingEnable": blend is not None, "BlendingValue": blend or 0}
    p.update({f"ArcPoint.{k}": v for k, v in zip(("X", "Y", "Z", "RX", "RY", "RZ"), (437.5, -102.3, 360.9, 180.0, 0.0, 90.0))})
    p.update({f"EndPoint.{k}": v for k, v in zip(("X", "Y", "Z", "RX", "RY", "RZ"), (457.5, -122.3, 360.9, 180.0, 0.0, 90.0))})
    return p


def test_move_circle_cap_faster_than_100_mm_s(bench):
    """V1 refuses any CAP circle above 100 mm/s (16#26, l.6050/6061); V2 checks mm/s for CAP."""
    b = bench("Circ")
    b.start("Circ", circle_params(speed=200))
    assert b.finish("Circ")["Done"]
    assert script_of(b.rx()[1])[1].startswith('Circle("CAP",437.50,-102.30,360.90,180.00,0.00,90.00,'
                                              '457.50,-122.30,360.90,180.00,0.00,90.00,200,200,0,0,false)')
    assert b.pose()[:2] == pytest.approx([457.5, -122.3], abs=1e-3)


@pytest.mark.parametrize(("params", "code"), [
    (circle_params(fmt="CPP_Circle", speed=101), 0x26),
    (circle_params(speed=4501), 0x25),
    (circle_params(accel=10000), 0x27),
    (circle_params(blend=101), 0x2A),
    (circle_params(arc=361), 0x2C),
])
def test_move_circle_parameter_checks(bench, params, code):
    b = bench("Circ")
    b.start("Circ", params)
    end = b.finish("Circ", 100)
    assert end["Error"] and end["ErrorID"] == code and len(b.rx()) == 1


def test_change_base_and_tcp(bench):
    b = bench("Base", "Tcp")
    b.start("Base", {"Transformation.X": 10.0, "Transformation.RZ": 90.0})
    assert b.finish("Base")["Done"]
    b.start("Tcp", {"TCPOffset.Z": 150.0, "Weight": 2.5, "MomentOfInertia.Ixx": 0.5, "MassCenter.Z": 80.0})
    assert b.finish("Tcp")["Done"]
    assert script_of(b.rx()[1])[1] == "ChangeBase(10.00,0.00,0.00,0.00,0.00,90.00)"
    assert script_of(b.rx()[2])[1] == ("ChangeTCP(0.00,0.00,150.00,0.00,0.00,0.00,2.50,0.50,0.00,0.00,"
                                       "0.00,0.00,80.00,0.00,0.00,0.00)")


def test_change_tcp_weight_range(bench):
    b = bench("Tcp")
    b.start("Tcp", {"Weight": 14.5})
    end = b.finish("Tcp", 100)
    assert end["ErrorID"] == 0x25 and len(b.rx()) == 1


def test_rejected_command_is_reported_with_the_robot_lines(bench):
    b = bench("Base", faults=["error:1"])
    b.start("Base", {"Transformation.X": 10.0})
    end = b.finish("Base")
    assert end["ErrorID"] == 0x80 and end["ErrorDescrip"] == "Command rejected: ERROR;1"


def test_no_reply_times_out(bench):
    b = bench("Base")
    b.transport.inject_fault("delay:5000")
    b.start("Base", {"Transformation.X": 10.0})
    end = b.finish("Base", 5000)
    assert end["ErrorID"] == 0x70 and end["ErrorDescrip"] == "No reply from robot"


def test_other_fb_under_execution(bench):
    b = bench("Abs", "Rel")
    b.start("Abs", move_params(target=(417.5, -122.3, 250.0, 180.0, 0.0, 90.0)))
    b.scan(5)
    b.start("Rel", rel_params())
    end = b.finish("Rel", 100)
    assert end["ErrorID"] == 0x11
    assert b.finish("Abs")["Done"]


def test_not_connected(bench):
    b = bench("Abs", connect=False)
    b.start("Abs", move_params())
    end = b.finish("Abs", 10)
    assert end["ErrorID"] == 0x10 and b.rx() == []


def test_execute_dropped_while_busy_shows_done_for_one_scan(bench):
    b = bench("Abs")
    b.start("Abs", move_params())
    b.scan(10)
    b.stop("Abs")
    b.until(lambda: b.get("T.Abs.Done"), 5000)
    b.scan(1)
    assert not b.get("T.Abs.Done") and not b.get("T.Abs.Busy")


# ------------------------------------------------------------------------- program control, new functions


def test_pause_and_resume_while_a_motion_waits(bench):
    b = bench("Abs", "Prg")
    b.start("Abs", move_params(target=(417.5, -122.3, 250.0, 180.0, 0.0, 90.0), speed=20))
    b.scan(100)
    b.start("Prg", {"Command": "Pause"})
    assert b.finish("Prg")["Done"]
    assert b.robot().paused
    held = b.pose()
    b.scan(500)
    assert b.pose() == held and b.get("T.Abs.Busy")
    b.stop("Prg")
    b.scan(2)
    b.start("Prg", {"Command": "Resume"})
    assert b.finish("Prg")["Done"] and not b.robot().paused
    assert b.finish("Abs")["Done"]
    assert [script_of(f)[1] for f in b.rx()[2:]] == ["Pause()", "Resume()"]


def test_stop_and_clear_aborts_the_waiting_motion(bench):
    b = bench("Abs", "Stop")
    b.start("Abs", move_params(target=(417.5, -122.3, 250.0, 180.0, 0.0, 90.0), speed=20))
    b.scan(100)
    b.start("Stop")
    assert b.finish("Stop")["Done"]
    end = b.finish("Abs", 10)
    assert end["ErrorID"] == 0x120 and end["ErrorDescrip"] == "Motion aborted: buffer cleared"
    assert not b.get("T.Cobot.WaitingReturn")
    assert script_of(b.rx()[2])[1] == "StopAndClearBuffer(0)"
    snap = b.robot().snapshot()
    assert not snap["moving"] and snap["queue_length"] == 0
    assert 250.0 < snap["pose"][2] < 360.0                # stopped on the way


def test_normal_stop_and_clear(bench):
    b = bench("Stop")
    b.start("Stop", StopPriority=False)
    assert b.finish("Stop")["Done"]
    assert script_of(b.rx()[1])[1] == "StopAndClearBuffer()"


def test_queued_digital_output_is_written_after_the_motion(bench):
    b = bench("Abs", "DOut")
    b.start("Abs", move_params(target=(417.5, -122.3, 300.0, 180.0, 0.0, 90.0), blend=50))
    assert b.finish("Abs")["Done"]                        # blended: Done at the OK, still moving
    b.start("DOut", DOutChannel=3, DOutValue=True)
    b.scan(5)
    assert b.robot().snapshot()["do"]["ControlBox"][3] == 0 and b.get("T.DOut.Busy")
    assert b.finish("DOut")["Done"]
    snap = b.robot().snapshot()
    assert snap["do"]["ControlBox"][3] == 1 and not snap["moving"]
    assert script_of(b.rx()[2])[1] == 'IO["ControlBox"].DO[3]=1\r\nQueueTag(1,0)'    # blended: no tag before


def test_instant_digital_output_on_the_end_module(bench):
    b = bench("DOut")
    b.start("DOut", DOutModule="EndModule", DOutChannel=2, DOutValue=True, DOutInstant=True)
    assert b.finish("DOut")["Done"]
    assert script_of(b.rx()[1])[1] == 'IO["EndModule"].InstantDO[2]=1'
    assert b.robot().snapshot()["do"]["EndModule"] == [0, 0, 1, 0]


@pytest.mark.parametrize(("module", "channel"), [("ControlBox", 16), ("EndModule", 4)])
def test_digital_output_channel_range(bench, module, channel):
    b = bench("DOut")
    b.start("DOut", DOutModule=module, DOutChannel=channel)
    end = b.finish("DOut", 10)
    assert end["ErrorID"] == 0x2D and len(b.rx()) == 1


def test_queue_tag_status(bench):
    b = bench("Abs", "TagQuery")
    b.start("TagQuery", TagNumber=5)
    assert b.finish("TagQuery")["Done"] and b.get("T.TagQuery.Status") == 0    # NoSuchTag
    b.stop("TagQuery")
    b.start("Abs", move_params(target=(417.5, -122.3, 250.0, 180.0, 0.0, 90.0)))
    b.scan(50)
    b.scan(2)
    b.start("TagQuery", TagNumber=1)
    assert b.finish("TagQuery")["Done"]
    assert b.get("T.TagQuery.Status") == 1                # NotReached: the motion of tag 1 runs
    b.stop("TagQuery")
    assert b.finish("Abs")["Done"]
    b.scan(2)
    b.start("TagQuery", TagNumber=1)
    assert b.finish("TagQuery")["Done"] and b.get("T.TagQuery.Status") == 2    # Reached
    assert b.rx()[1] == tm_frame("TMSTA", "01,05")


def test_queue_tag_status_range(bench):
    b = bench("TagQuery")
    b.start("TagQuery", TagNumber=16)
    assert b.finish("TagQuery", 10)["ErrorID"] == 0x2E


def test_exit_node_then_commands_wait_for_the_node(bench):
    b = bench("Abs", "ExitNode", settings=emulator.EmulatorSettings(reenter_delay_ms=500))
    b.start("ExitNode")
    assert b.finish("ExitNode")["Done"]
    assert not b.get("T.Cobot.InListenNode") and b.get("T.Cobot.Connected")
    b.start("Abs", move_params())
    assert b.finish("Abs", 10)["ErrorID"] == 0x12
    b.stop("Abs")
    b.until(lambda: b.get("T.Cobot.InListenNode"), 2000, "re-entry")    # entry message $TMSCT,9,0,Listen1
    b.scan(2)
    b.start("Abs", move_params())
    assert b.finish("Abs")["Done"]
    assert script_of(b.rx()[1])[1] == "ScriptExit()"


# ------------------------------------------------------------------------- codes of the docs/robotlibs_cbt_v2.md table (issue 31)


def test_motion_reported_failed_is_16_110():
    """The robot reports the motion's QueueTag false (emulator fault tag_false): 16#110 motion failed."""
    b = V2Bench("Abs", faults=["tag_false"])
    try:
        b.start("Abs", move_params(target=(417.5, -122.3, 300.0, 180.0, 0.0, 90.0)))
        end = b.finish("Abs")
        assert end["Error"] and end["ErrorID"] == 0x110 and not end["Done"]
    finally:
        b.close()


def test_cperr_answer_is_16_81():
    """The robot answers CPERR (a frame longer than its max_data_length): 16#81."""
    b = V2Bench("Abs", settings=emulator.EmulatorSettings(max_data_length=40))
    try:
        b.start("Abs", move_params(target=(417.5, -122.3, 300.0, 180.0, 0.0, 90.0)))
        end = b.finish("Abs")
        assert end["Error"] and end["ErrorID"] == 0x81
    finally:
        b.close()
