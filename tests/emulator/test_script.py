"""Script parser and static checks (spec §4.1, §4.2, §4.5, §7)."""

from __future__ import annotations

import pytest

from emulator import script as sc

THESIS_LINES = [
    # What the thesis FBs send (Annex A), including Sysmac's signed whole numbers (sysmac.md §8.13).
    'PTP("CPP",+417,-122,+344,+180,+0,+90,10,200,0,false,0,2,4)',
    'PTP("JPP",+0,+0,+90,+0,+90,+0,35,200,0,false)',
    'Line("CAR",+417,-122,+344,+180,+0,+90,100,200,50,false)',
    'Move_PTP("TPP",+0,+0,+10,+45,+0,+0,10,200,0,false)',
    'Move_Line("TPP",+0,+0,+10,+45,+0,+0,10,200,0,false)',
    'Circle("CAP",+417,-122,+344,+180,+0,+90,+381,+208,+344,+180,+0,+135,100,200,50,270,false)',
    'ChangeBase(+20,+30,+10,+0,+0,+90)',
    'ChangeTCP(+0,+0,+150,+0,+0,+90,2,2,0.5,0.5,0,0,-80,0,0,0)',
    'QueueTag(8,0)', 'QueueTag(8)', 'Pause()', 'Resume()', 'ScriptExit()',
]

CLIENT_LINES = [
    # techmanpy 1.2 and pytmrobot 0.2.2 (spec §10).
    'PTP("JPP",0,0,90,0,90,0,10,200,0,true)',
    'Line("CAP",417.5,-122.3,343.9,180,0,90,100,200,0,true)',
    'PTP("CPP",{400.0,-100.0,350.0,180.0,0.0,90.0},30,200,0,false)',
    'Line("CDP",{450.0,-100.0,350.0,180.0,0.0,90.0},150,200,0,false)',
    'Circle("CPP",1,2,3,4,5,6,7,8,9,10,11,12,50,200,0,90,true)',
    'PLine("CAP",400,-100,350,180,0,90,100,200,0)', 'Move_PLine("TAP",0,0,10,0,0,0,100,200,0)',
    'ChangeBase("RobotBase")', 'ChangeTCP("NOTOOL")', 'ChangeLoad(10.1)', 'WaitQueueTag(2,1000)',
    'StopAndClearBuffer()', 'StopAndClearBuffer(0)', 'ScriptExit(1)', 'Sleep(500)',
    'ListenSend(90, GetString(Robot[0].CoordRobot[0])+","+GetString(Robot[0].CoordRobot[1]))',
    'ListenSend(90, GetString(Robot[0].TCPSpeed3D))',
]


@pytest.mark.parametrize("line", THESIS_LINES + CLIENT_LINES)
def test_accepts_every_function_the_thesis_and_clients_send(line: str) -> None:
    parsed = sc.parse_script(line)
    assert parsed.error_lines == ()


@pytest.mark.parametrize(("script", "errors"), [
    ("NoSuchFunction()", (1,)),
    ('PTP("JPP",0,0,90)', (1,)),                       # wrong argument count
    ('QueueTag(1)\r\nLine("CAP",1,2,3)\r\nX(', (2, 3)),  # all error lines reported
    ("QueueTag(1)\rQueueTag(2)", (1,)),                # bare CR is no separator (§4.1)
    ("QueueTag(1)\nQueueTag(2)", (1,)),
    ('PTP(\u201dJPP\u201d,0,0,90,0,90,0,10,200,0,false)', (1,)),  # typographic quotes
    ("var_x = 1", (1,)),                               # undeclared
    ("int a = 1\r\nint a = 2", (2,)),                  # re-declared (§4.1)
    ("StopAndClearBuffer(var_st)", (1,)),              # priority needs a literal (§4.5)
    ("ScriptExit(3)", (1,)),
    ('ptp("JPP",0,0,90,0,90,0,10,200,0,false)', (1,)),  # function names are case-sensitive
    ('PTP("JPP",0,0,90,0,90,0,10,200,0,1)', (1,)),     # disablePrecise must be a bool
])
def test_static_errors(script: str, errors: tuple[int, ...]) -> None:
    assert sc.parse_script(script).error_lines == errors


def test_session_variables_and_trailing_crlf() -> None:
    parsed = sc.parse_script("int var_i = 100\r\nvar_i = 1000\r\nvar_i++\r\n")
    assert parsed.error_lines == () and parsed.declared == ("var_i",)
    assert sc.parse_script("int var_i = 1", {"var_i": ("int", False)}).error_lines == (1,)
    assert sc.parse_script("var_i += 2", {"var_i": ("int", False)}).error_lines == ()


def test_arrays_and_expressions() -> None:
    parsed = sc.parse_script('float[] targetP1 = {0,0,90,0,90,0}\r\nPTP("JPP",targetP1,10,200,0,false)\r\n'
                             'int n = (1 + 2) * 3 % 4\r\nbool b = n >= 2 && !false')
    assert parsed.error_lines == ()


def test_empty_script_is_ok() -> None:
    assert sc.parse_script("") == sc.ParsedScript((), ())


@pytest.mark.parametrize(("script", "name", "mode"), [
    ("ScriptExit(0)", "ScriptExit", 0), ("ScriptExit(1)", "ScriptExit", 1),
    ("StopAndClearBuffer(2)", "StopAndClearBuffer", 2),
    ("StopAndClearBuffer(1)\r\nScriptExit(0)", "ScriptExit", 0),  # ScriptExit wins (§4.5)
    ("StopAndClearBuffer(0)\r\nStopAndClearBuffer(2)", "StopAndClearBuffer", 0),  # first counts
])
def test_priority_detection(script: str, name: str, mode: int) -> None:
    priority = sc.parse_script(script).priority
    assert priority is not None and (priority.name, priority.mode) == (name, mode)


def test_normal_script_exit_is_not_priority() -> None:
    assert sc.parse_script("ScriptExit()").priority is None


@pytest.mark.parametrize(("text", "value"), [("123", 123), ("34.567", 34.567), ("3.4e5", 3.4e5),
                                             ("0x1F", 31), ("0b101", 5)])
def test_numbers(text: str, value: float) -> None:
    assert sc.parse_number(text) == value
