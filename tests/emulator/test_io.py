"""Digital I/O objects of TM scripts (emulator/builtins.py io_read / io_write; TM Expression Editor
manual 7.5 IO, p.222-224): IO["ControlBox"] / IO["EndModule"] DI (read), DO (queued write: written
when the motions queued before it have finished) and InstantDO (written when the line runs)."""

from __future__ import annotations

import pytest

from emulator.framing import encode
from test_robot import MS, Driver

MOVE = 'PTP("JPP",0,0,90,0,90,60,100,200,0,false)'


@pytest.fixture
def d() -> Driver:
    drv = Driver()
    drv.connect()
    return drv


def outputs(d: Driver, module: str = "ControlBox") -> list[int]:
    return d.robot.snapshot()["do"][module]


def test_queued_do_is_written_after_the_motion_before_it(d: Driver) -> None:
    assert d.sct(f'1,{MOVE}\r\nIO["ControlBox"].DO[3]=1\r\nQueueTag(1)') == [encode("TMSCT", "1,OK")]
    d.advance(20 * MS)
    assert outputs(d)[3] == 0                                 # the motion still runs
    sends = d.run_until_idle()
    assert [s.data for s in sends] == [encode("TMSTA", "01,01,true")]
    assert outputs(d) == [0, 0, 0, 1] + [0] * 12


def test_instant_do_is_written_at_once(d: Driver) -> None:
    d.sct(f'1,{MOVE}\r\nIO["EndModule"].InstantDO[2]=1')
    assert outputs(d, "EndModule") == [0, 0, 1, 0]


def test_outputs_and_inputs_read_back(d: Driver) -> None:
    d.sct('1,IO["ControlBox"].InstantDO[5]=1')
    assert d.sct('2,ListenSend(90,GetString(IO["ControlBox"].DO))') == [
        encode("TMSTA", "90,{0,0,0,0,0,1,0,0,0,0,0,0,0,0,0,0}"), encode("TMSCT", "2,OK")]
    assert d.sct('3,byte b = IO["ControlBox"].DO[5]\r\nListenSend(91,GetString(b))')[0] == encode("TMSTA", "91,1")
    assert d.sct('4,ListenSend(92,GetString(IO["EndModule"].DI))')[0] == encode("TMSTA", "92,{0,0,0,0}")


@pytest.mark.parametrize("statement", [
    'IO["ControlBox"].DO[16]=1',        # ControlBox has DO 0..15
    'IO["EndModule"].DO[4]=1',          # EndModule has DO 0..3
    'IO["ControlBox"].DO[0]=2',         # 0 or 1
    'IO["controlbox"].DO[0]=1',         # module names as the manual writes them
    'IO["Safety"].DO[0]=1',             # not modelled
    'IO["ControlBox"].DI[0]=1',         # inputs are read-only
    'IO["ControlBox"].DO=1',            # a whole array
    'IO["ControlBox"].DO[0]+=1',
    'IO["ControlBox"].AO[0]=1',         # analog I/O is not modelled
])
def test_invalid_io_is_an_error_and_runs_nothing(d: Driver, statement: str) -> None:
    assert d.sct(f"7,{statement}") == [encode("TMSCT", "7,ERROR;1")]
    assert outputs(d) == [0] * 16 and outputs(d, "EndModule") == [0] * 4


def test_stop_and_clear_drops_a_queued_do(d: Driver) -> None:
    d.sct(f'1,{MOVE}\r\nIO["ControlBox"].DO[1]=1')
    d.advance(10 * MS)
    d.sct("2,StopAndClearBuffer()")
    d.run_until_idle()
    assert outputs(d)[1] == 0
