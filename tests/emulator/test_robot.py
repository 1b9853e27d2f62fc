"""Robot behaviour (spec §1, §4, §5, §8, §9): pure Robot driven with frames and explicit times."""

from __future__ import annotations

import pytest

from emulator.faults import FaultPlan
from emulator.framing import ListenNodeFramer, decode_all, encode
from emulator.robot import Close, NodeState, Robot, Send
from emulator.settings import EmulatorSettings

MS = 1_000_000
S = 1_000_000_000


class Driver:
    def __init__(self, settings: EmulatorSettings = EmulatorSettings(), faults: FaultPlan = FaultPlan()):
        self.robot = Robot(settings, faults)
        self.framer = ListenNodeFramer(settings)
        self.t = 0

    def connect(self, conn: int = 1) -> list[bytes]:
        return self._data(self.robot.connect(conn, self.t))

    def send(self, wire: bytes | str, conn: int = 1, at: int | None = None) -> list[bytes]:
        if at is not None:
            self.t = at
        wire = wire.encode() if isinstance(wire, str) else wire
        out = []
        for result in decode_all(self.framer, wire)[0]:
            out += self.robot.handle(conn, result, self.t)
        return self._data(out)

    def sct(self, data: str, conn: int = 1) -> list[bytes]:
        return self.send(encode("TMSCT", data), conn)

    def sta(self, data: str, conn: int = 1) -> list[bytes]:
        return self.send(encode("TMSTA", data), conn)

    def advance(self, to_ns: int) -> list[Send]:
        self.t = to_ns
        return [a for a in self.robot.advance(to_ns) if isinstance(a, Send)]

    def run_until_idle(self, limit_ns: int = 60 * S) -> list[Send]:
        return self.advance(self.t + limit_ns)

    @staticmethod
    def _data(actions) -> list[bytes]:
        return [a.data for a in actions if isinstance(a, Send)]


@pytest.fixture
def d() -> Driver:
    drv = Driver()
    drv.connect()
    return drv


def test_thesis_exchange_section_9_1() -> None:
    d = Driver(EmulatorSettings(after_exit="stay"))  # flow does not loop back into the node
    d.connect()
    assert d.send("$TMSTA,2,00,*41\r\n") == [b"$TMSTA,15,00,true,Listen1,*79\r\n"]
    assert d.send('$TMSCT,88,2,PTP("CPP",417.50,-122.30,343.90,180.00,0.00,90.00,10,200,0,false,0,2,4)'
                  "\r\nQueueTag(2,0),*23\r\n") == [b"$TMSCT,4,2,OK,*5F\r\n"]
    assert [s.data for s in d.run_until_idle()] == [b"$TMSTA,10,01,02,true,*67\r\n"]
    assert d.send('$TMSCT,85,3,Line("CAR",417.50,-122.30,343.90,180.00,0.00,90.00,100,200,50,false)'
                  "\r\nQueueTag(3,0),*58\r\n") == [b"$TMSCT,4,3,OK,*5E\r\n"]
    assert [s.data for s in d.run_until_idle()] == [b"$TMSTA,10,01,03,true,*66\r\n"]
    assert d.send("$TMSCT,9,5,Pause(),*02\r\n") == [b"$TMSCT,4,5,OK,*58\r\n"]
    assert d.send("$TMSCT,10,6,Resume(),*52\r\n") == [b"$TMSCT,4,6,OK,*5B\r\n"]
    assert d.send('$TMSCT,70,4,PTP("JPP",0,0,90,0,90,0,35,200,0,false)\r\nQueueTag(4,0)\r\nScriptExit(),*2C\r\n') == []
    assert [s.data for s in d.run_until_idle()] == [b"$TMSTA,10,01,04,true,*61\r\n", b"$TMSCT,4,4,OK,*59\r\n"]
    assert d.send("$TMSCT,9,5,Pause(),*02\r\n") == [b"$CPERR,2,F1,*3F\r\n"]


@pytest.mark.parametrize(("request_wire", "reply"), [
    (b'$TMSCT,25,1,ChangeBase("RobotBase"),*08\r\n', b"$TMSCT,4,1,OK,*5C\r\n"),
    (b'$TMSCT,64,2,ChangeBase("RobotBase")\r\nChangeTCP("NOTOOL")\r\nChangeLoad(10.1),*68\r\n', b"$TMSCT,4,2,OK,*5F\r\n"),
    (b"$TMSCT,40,3,int var_i = 100\r\nvar_i = 1000\r\nvar_i++,*5A\r\n", b"$TMSCT,4,3,OK,*5E\r\n"),
    (b"$TMSCT,42,4,int var_i = 100\r\nvar_i = 1000\r\nvar_i++\r\n,*58\r\n", b"$TMSCT,4,4,OK,*59\r\n"),
    (b"$TMSCT,53,8,ChangeTCP(0,0,150,0,0,90,2,2,0.5,0.5,0,0,-80,0,0,0),*07\r\n", encode("TMSCT", "8,OK")),
    (b'$TMSCT,116,9,Circle("CAP",417.50,-122.30,343.90,180.00,0.00,90.00,381.70,208.74,343.90,180.00,0.00,'
     b'135.00,100,200,50,270,false),*43\r\n', encode("TMSCT", "9,OK")),
    (b'$TMSCT,46,2,Move_PTP("TPP",0,0,10,45,0,0,10,200,0,false),*7C\r\n', b"$TMSCT,4,2,OK,*5F\r\n"),
    (b'$TMSCT,47,3,Move_Line("TPP",0,0,10,45,0,0,10,200,0,false),*06\r\n', b"$TMSCT,4,3,OK,*5E\r\n"),
    (b"$TMSCT,22,7,StopAndClearBuffer(),*61\r\n", b"$TMSCT,4,7,OK,*5A\r\n"),
    (b"$TMSTA,3,00,,*6c\r\n", b"$TMSTA,15,00,true,Listen1,*79\r\n"),
    (b"$TMSTA,5,01,15,*6F\r\n", b"$TMSTA,10,01,15,none,*7D\r\n"),
    (b"$TMSTA,4,XXXX,*47\r\n", b"$CPERR,2,04,*4C\r\n"),
    (b'$TMSCT,23,ChangeBase("RobotBase"),*13\r\n', b"$CPERR,2,04,*4C\r\n"),
    (b"$TMSTA,14,90,Hello World,*73\r\n", b"$CPERR,2,04,*4C\r\n"),  # §11 #12
])
def test_vectors_section_9_2(d: Driver, request_wire: bytes, reply: bytes) -> None:
    assert d.send(request_wire) == [reply]


def test_queue_tag_on_idle_queue_fires_at_once(d: Driver) -> None:
    # Real tmr_ros2 log (spec S9); nothing queued before the tag, so it is reached immediately.
    assert d.send(b"$TMSCT,17,Tag,QueueTag(1,0),*26\r\n") == [b"$TMSCT,6,Tag,OK,*3D\r\n",
                                                             b"$TMSTA,10,01,01,true,*64\r\n"]


def test_empty_script_keep_alive(d: Driver) -> None:
    assert d.sct("3,") == [encode("TMSCT", "3,OK")]  # §4.1, §11 #13


def test_status_outside_node_and_f1() -> None:
    drv = Driver(EmulatorSettings(start_in_node=False))
    drv.connect()
    assert drv.send("$TMSTA,2,00,*41\r\n") == [b"$TMSTA,9,00,false,,*37\r\n"]
    assert drv.send(b'$TMSCT,25,1,ChangeBase("RobotBase"),*08\r\n') == [b"$CPERR,2,F1,*3F\r\n"]


def test_entry_message_on_entry_only(d: Driver) -> None:
    drv = Driver(EmulatorSettings(enter_node_delay_ms=100))
    drv.connect(1)
    assert [s.data for s in drv.advance(100 * MS)] == [b"$TMSCT,9,0,Listen1,*4C\r\n"]
    assert drv.connect(2) == []  # §11 #1: a later client is not greeted


def test_queue_tag_wait_notification_before_ok(d: Driver) -> None:
    d.sct('1,PTP("JPP",0,0,90,0,90,30,100,200,0,false)')
    assert d.sct("2,QueueTag(1,1)") == []
    assert [s.data for s in d.run_until_idle()] == [b"$TMSTA,10,01,01,true,*64\r\n", b"$TMSCT,4,2,OK,*5F\r\n"]


def test_queue_tag_wait_ok_first_setting() -> None:
    drv = Driver(EmulatorSettings(notify_before_ok=False))
    drv.connect()
    drv.sct('1,PTP("JPP",0,0,90,0,90,30,100,200,0,false)')
    drv.sct("2,QueueTag(1,1)")
    assert [s.data for s in drv.run_until_idle()] == [b"$TMSCT,4,2,OK,*5F\r\n", b"$TMSTA,10,01,01,true,*64\r\n"]


def test_tag_status_query_and_memory(d: Driver) -> None:
    d.sct('1,PTP("JPP",0,0,90,0,90,30,100,200,0,false)\r\nQueueTag(1)')
    assert d.send(b"$TMSTA,5,01,01,*6A\r\n") == [b"$TMSTA,11,01,01,false,*0E\r\n"]
    d.run_until_idle()
    assert d.sta("01,1") == [b"$TMSTA,9,01,1,true,*6C\r\n"]  # §11 #3: tag text echoed
    for tag in (2, 3, 4, 5):
        d.sct(f"{tag},QueueTag({tag})")
    assert d.sta("01,01") == [encode("TMSTA", "01,01,none")]  # only the last 4 tags remembered
    assert d.sta("01,5") == [encode("TMSTA", "01,5,true")]


def test_motions_run_fifo_and_tags_fire_in_order(d: Driver) -> None:
    d.sct('1,PTP("JPP",0,0,90,0,90,30,100,200,0,false)\r\nQueueTag(1)\r\n'
          'PTP("JPP",0,0,90,0,90,0,100,200,0,false)\r\nQueueTag(2)')
    sends = d.run_until_idle()
    assert [s.data for s in sends] == [encode("TMSTA", "01,01,true"), encode("TMSTA", "01,02,true")]
    assert sends[0].at_ns < sends[1].at_ns


def test_pause_holds_motion_and_tags(d: Driver) -> None:
    d.sct('1,PTP("JPP",0,0,90,0,90,30,100,200,0,false)\r\nQueueTag(1)')
    plain = Driver()
    plain.connect()
    plain.sct('1,PTP("JPP",0,0,90,0,90,30,100,200,0,false)\r\nQueueTag(1)')
    done_at = plain.run_until_idle()[0].at_ns
    d.advance(50 * MS)
    d.sct("2,Pause()")
    assert d.advance(50 * MS + done_at) == []  # paused: nothing fires
    d.sct("3,Resume()")
    sends = d.run_until_idle()
    assert sends[0].data == encode("TMSTA", "01,01,true")
    assert sends[0].at_ns == done_at + done_at  # held for exactly the paused time


def test_stop_and_clear_drops_tags_without_notification(d: Driver) -> None:
    d.sct('1,PTP("JPP",0,0,90,0,90,60,100,200,0,false)\r\nQueueTag(1)')
    d.advance(10 * MS)
    assert d.sct("2,StopAndClearBuffer()") == [encode("TMSCT", "2,OK")]
    assert d.run_until_idle() == []
    assert d.sta("01,1") == [encode("TMSTA", "01,1,false")]  # §11 #7


def test_priority_script_exit_interrupts_blocked_script(d: Driver) -> None:
    d.sct('1,PTP("JPP",0,0,90,0,90,60,100,200,0,false)\r\nQueueTag(1,1)')
    d.sct("3,QueueTag(2)")  # buffered behind the blocked script
    assert d.sct("2,ScriptExit(0)") == [b"$TMSCT,4,1,OK,*5C\r\n", b"$TMSCT,4,2,OK,*5F\r\n"]
    assert d.robot.state == NodeState.RUNNING and d.robot.exit_path == "Fail"
    assert d.sta("00") == [b"$TMSTA,9,00,false,,*37\r\n"]


def test_reenter_after_exit_sends_entry_message_again(d: Driver) -> None:
    assert d.sct("1,ScriptExit()") == [encode("TMSCT", "1,OK")]
    sends = d.advance(d.t + 2 * S)
    assert [(s.data, s.at_ns) for s in sends] == [(b"$TMSCT,9,0,Listen1,*4C\r\n", 1000 * MS)]


def test_script_exit_drains_and_blocks_new_scripts(d: Driver) -> None:
    d.sct('1,PTP("JPP",0,0,90,0,90,30,100,200,0,false)\r\nScriptExit()\r\nChangeLoad(10.1)')
    assert d.robot.state == NodeState.EXITING
    assert d.sct("2,Pause()") == [b"$CPERR,2,F1,*3F\r\n"]  # §4.6
    assert d.sta("00") == [b"$TMSTA,9,00,false,,*37\r\n"]
    assert [s.data for s in d.run_until_idle()][0] == encode("TMSCT", "1,OK")
    assert d.robot.payload_kg == 0.0  # ChangeLoad after ScriptExit() never ran


@pytest.mark.parametrize("script", [
    'PTP("XYZ",0,0,90,0,90,0,10,200,0,false)',       # unknown format
    'PTP("JAP",0,0,90,0,90,0,10,200,0,false)',       # JAP passed to PTP
    'PTP("JPP",0,0,90,0,90,0,101,200,0,false)',      # speed out of range
    "QueueTag(16)",                                   # tag > 15
    'PTP("CPP",2000,0,0,180,0,0,10,200,0,false)',    # unreachable
    'PTP("JPP",0,0,200,0,90,0,10,200,0,false)',      # joint limit
    'PTP("JPP",0,0,90,0,90,0,10,200,0,false,0,2,4)',  # pose config only with CPP
    'ChangeBase("NoSuchBase")',
    'Line("CPP",{1,2,3},10,200,0,false)',             # array of 3
])
def test_invalid_arguments_answer_error_and_run_nothing(d: Driver, script: str) -> None:
    assert d.sct(f"5,QueueTag(1)\r\n{script}") == [encode("TMSCT", "5,ERROR;2")]
    assert d.sta("01,1") == [encode("TMSTA", "01,1,none")]  # line 1 did not run


def test_reject_invalid_args_off_answers_ok() -> None:
    drv = Driver(EmulatorSettings(reject_invalid_args=False))
    drv.connect()
    assert drv.sct("5,QueueTag(16)") == [encode("TMSCT", "5,OK")]


def test_redeclared_session_variable(d: Driver) -> None:
    assert d.sct("3,int var_i = 100") == [encode("TMSCT", "3,OK")]
    assert d.sct("4,int var_i = 100") == [b"$TMSCT,9,4,ERROR;1,*02\r\n"]


def test_several_clients_get_their_own_replies() -> None:
    drv = Driver()
    drv.connect(1)
    drv.connect(2)
    out = drv.robot.handle(2, decode_all(drv.framer, encode("TMSCT", "7,QueueTag(3)"))[0][0], 0)
    assert [(a.conn, a.data) for a in out] == [(2, encode("TMSCT", "7,OK")), (2, encode("TMSTA", "01,03,true"))]


def test_tag_broadcast_setting() -> None:
    drv = Driver(EmulatorSettings(tag_notify_broadcast=True))
    drv.connect(1)
    drv.connect(2)
    actions = drv.robot.handle(1, decode_all(drv.framer, encode("TMSCT", "7,QueueTag(3)"))[0][0], 0)
    assert sorted(a.conn for a in actions if a.data.startswith(b"$TMSTA")) == [1, 2]


def test_listen_send_and_robot_members(d: Driver) -> None:
    out = d.sct('1,ListenSend(90, GetString(Robot[0].CoordRobot[0])+","+GetString(Robot[0].Joint[2]))')
    assert out == [encode("TMSTA", "90,417.5,90"), encode("TMSCT", "1,OK")]
    assert d.sct('2,ListenSend(90,"Hello World")')[0] == b"$TMSTA,14,90,Hello World,*73\r\n"


def test_data_timeout_takes_fail_path() -> None:
    drv = Driver(EmulatorSettings(data_timeout_ms=500, after_exit="stay"))
    drv.connect()
    drv.advance(499 * MS)
    assert drv.robot.state == NodeState.IN_NODE
    drv.advance(500 * MS)
    assert drv.robot.state == NodeState.RUNNING and drv.robot.exit_path == "Fail"


def test_after_exit_stop_closes_everything() -> None:
    drv = Driver(EmulatorSettings(after_exit="stop"))
    drv.connect()
    actions = drv.robot.handle(1, decode_all(drv.framer, encode("TMSCT", "1,ScriptExit(1)"))[0][0], 0)
    assert any(isinstance(a, Close) and a.conn is None for a in actions)
    assert not drv.robot.accepting


def test_fault_error_and_tag_false() -> None:
    drv = Driver(faults=FaultPlan(answer_error_every=2, tag_false=True))
    drv.connect()
    assert drv.sct("1,QueueTag(1)") == [encode("TMSCT", "1,OK"), encode("TMSTA", "01,01,false")]
    assert drv.sct("2,QueueTag(2)") == [encode("TMSCT", "2,ERROR;1")]


def test_fault_busy_never_finishes() -> None:
    drv = Driver(faults=FaultPlan(stay_busy=True))
    drv.connect()
    drv.sct('1,PTP("JPP",0,0,90,0,90,30,100,200,0,false)\r\nQueueTag(1)')
    assert drv.advance(100 * S) == []


def test_snapshot_is_plain_data(d: Driver) -> None:
    snap = d.robot.snapshot()
    assert snap["state"] == "IN_NODE" and len(snap["pose"]) == 6 and snap["connections"] == [1]
