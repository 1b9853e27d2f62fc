"""The CODESYS Util blocks (stvm/stdlib/cds_util.st, `--dialect codesys`): HYSTERESIS,
LIMITALARM, BLINK on the virtual clock; the shift count of SHL/SHR/ROL/ROR may be a BYTE under
codesys and twincat (the vendors' own examples); Tc2_Utilities TIMESTRUCT."""

from __future__ import annotations

import pytest

from stvm.project import LoadError, load
from stvm.settings import DEFAULT_SETTINGS
from tests.core_helpers import write_files

CODESYS = DEFAULT_SETTINGS.with_table({"dialect": "codesys"}, "test")
TWINCAT = DEFAULT_SETTINGS.with_table({"dialect": "twincat"}, "test")

UTIL = """
PROGRAM Main
VAR
    value : INT;
    hyst : HYSTERESIS;
    alarm : LIMITALARM;
    blinker : BLINK;
    enable : BOOL;
END_VAR
hyst(IN := value, HIGH := 80, LOW := 20);
alarm(IN := value, HIGH := 80, LOW := 20);
blinker(ENABLE := enable, TIMELOW := T#20ms, TIMEHIGH := T#30ms);
END_PROGRAM
"""


def _util():
    return load(write_files({"main.st": UTIL}), CODESYS, use_cache=False).start(scan="10ms")


def test_hysteresis_switches_below_low_and_above_high_only() -> None:
    vm = _util()
    seen = []
    for value in (50, 10, 50, 79, 81, 50, 19):
        vm["Main.value"] = value
        vm.run(cycles=1)
        seen.append(vm["Main.hyst.OUT"])
    # CODESYS help: TRUE once IN < LOW, FALSE once IN > HIGH, unchanged in between
    assert seen == [False, True, True, True, False, False, True]


@pytest.mark.parametrize("value, flags", [(90, (True, False, False)), (10, (False, True, False)),
                                          (80, (False, False, True)), (20, (False, False, True))])
def test_limit_alarm(value, flags) -> None:
    vm = _util()
    vm["Main.value"] = value
    vm.run(cycles=1)
    assert (vm["Main.alarm.O"], vm["Main.alarm.U"], vm["Main.alarm.IL"]) == flags


def test_blink_is_high_for_timehigh_then_low_for_timelow() -> None:
    vm = _util()
    vm.run(cycles=2)
    assert vm["Main.blinker.OUT"] is False          # not enabled: FALSE
    vm["Main.enable"] = True
    outs = []
    for _ in range(12):
        vm.run(cycles=1)
        outs.append(vm["Main.blinker.OUT"])
    # 10 ms scans: 3 scans high (30 ms), 2 low (20 ms), and again
    assert outs == [True, True, True, False, False, True, True, True, False, False, True, True]
    vm["Main.enable"] = False
    vm.run(cycles=1)
    assert vm["Main.blinker.OUT"] is False


def test_util_is_codesys_only() -> None:
    with pytest.raises(LoadError) as info:
        load(write_files({"main.st": UTIL}), TWINCAT, use_cache=False)
    assert "HYSTERESIS" in info.value.render()


SHIFTS = """
PROGRAM Main
VAR
    n : BYTE := 2;
    inByte : BYTE := 16#45;
    inWord : WORD := 16#0045;
    b : BYTE;
    w : WORD;
    r : BYTE;
    when : TIMESTRUCT;
END_VAR
b := SHL(inByte, n);
w := SHL(inWord, n);
r := ROL(inByte, n);
when.wYear := 2024;
when.wDayOfWeek := 0;
END_PROGRAM
"""


def test_shift_by_a_byte_as_in_the_vendor_examples() -> None:
    vm = load(write_files({"main.st": SHIFTS}), TWINCAT, use_cache=False).start()
    vm.run(cycles=1)
    # CODESYS/Beckhoff help "SHL": 16#45 by 2 is 16#14 in a BYTE, 16#0114 in a WORD; ROL 16#15
    assert (vm["Main.b"], vm["Main.w"], vm["Main.r"]) == (0x14, 0x114, 0x15)
    assert vm["Main.when.wYear"] == 2024


RAMPS = """
PROGRAM Main
VAR
    target : REAL := 100.0;
    reset : BOOL;
    timed : RAMP_REAL;
    perCall : RAMP_INT;
END_VAR
timed(IN := target, ASCEND := 10.0, DESCEND := 40.0, TIMEBASE := T#100ms, RESET := reset);
perCall(IN := REAL_TO_INT(target), ASCEND := 10, DESCEND := 5, TIMEBASE := T#0s, RESET := reset);
END_PROGRAM
"""


def test_ramps_limit_the_slope() -> None:
    vm = load(write_files({"main.st": RAMPS}), CODESYS, use_cache=False).start(scan="10ms")
    vm.run(cycles=11)     # timed: the first call takes the time, then 10 calls of 10 ms = one TIMEBASE
    assert vm["Main.timed.OUT"] == pytest.approx(10.0)
    assert vm["Main.perCall.OUT"] == 100        # 10 per call: reached after 10 calls, then held
    vm["Main.target"] = 0.0
    vm.run(cycles=2)
    assert vm["Main.timed.OUT"] == pytest.approx(10.0 - 2 * 4.0)    # DESCEND 40 per 100 ms: 4 per 10 ms
    assert vm["Main.perCall.OUT"] == 90
    vm["Main.reset"] = True
    vm.run(cycles=3)
    assert vm["Main.perCall.OUT"] == 90          # RESET stops the ramp and keeps OUT
    vm["Main.reset"] = False
    vm.run(cycles=1)
    assert vm["Main.perCall.OUT"] == 85          # and it goes on from there


CURVE = """
PROGRAM Main
VAR
    curve : CHARCURVE;
    KL : ARRAY[0..10] OF POINT := [(X:=0,Y:=0),(X:=250,Y:=50),(X:=500,Y:=150),(X:=750,Y:=400), 7((X:=1000,Y:=1000))];
    bad : ARRAY[0..10] OF POINT := [(X:=0,Y:=0),(X:=500,Y:=50),(X:=400,Y:=150), 8((X:=1000,Y:=1000))];
    input : INT;
    n : BYTE := 5;
    useBad : BOOL;
END_VAR
IF useBad THEN
    curve(IN := input, N := n, P := bad);
ELSE
    curve(IN := input, N := n, P := KL);
END_IF
END_PROGRAM
"""


@pytest.mark.parametrize("value, n, bad, out, err", [
    (600, 5, False, 250, 0),       # between (500, 150) and (750, 400)
    (125, 5, False, 25, 0),
    (1000, 5, False, 1000, 0),
    (-10, 5, False, 0, 2),         # below the first X: the first Y, ERR 2
    (1200, 5, False, 1000, 2),     # beyond the last X: the last Y
    (300, 1, False, 0, 4),         # N outside 2..11
    (450, 3, True, 45, 0),         # in the first segment: the bad order later is not seen yet
    (600, 3, True, 0, 1),          # past the second point, to the third whose X goes back: ERR 1
])
def test_characteristic_curve(value, n, bad, out, err) -> None:
    vm = load(write_files({"main.st": CURVE}), CODESYS, use_cache=False).start()
    vm["Main.input"], vm["Main.n"], vm["Main.useBad"] = value, n, bad
    vm.run(cycles=1)
    assert (vm["Main.curve.OUT"], vm["Main.curve.ERR"]) == (out, err)


CONTROL = """
PROGRAM Main
VAR
    fixed : PID_FIXCYCLE;
    timed : PID;
    setPoint : REAL := 1.0;
    actual : REAL;
    manual, reset : BOOL;
    yMax : REAL := 10.0;
END_VAR
fixed(ACTUAL := actual, SET_POINT := setPoint, KP := 2.0, TN := 1.0, TV := 0.5, Y_MANUAL := 7.0, Y_OFFSET := 0.5,
      Y_MIN := 0.0, Y_MAX := yMax, MANUAL := manual, RESET := reset, CYCLE := 0.1);
timed(ACTUAL := actual, SET_POINT := setPoint, KP := 2.0, TN := 1.0, TV := 0.0, Y_MIN := 0.0, Y_MAX := yMax);
END_PROGRAM
"""


def test_pid_fixcycle_and_pid() -> None:
    vm = load(write_files({"main.st": CONTROL}), CODESYS, use_cache=False).start(scan="100ms")
    vm.run(cycles=3)
    # e = 1 constant: integral 3 * 0.1 s; no derivative of a constant error; Y_OFFSET added
    assert vm["Main.fixed.Y"] == pytest.approx(2.0 * (1.0 + 0.3) + 0.5)
    assert vm["Main.timed.Y"] == pytest.approx(2.0 * (1.0 + 0.2))   # the first call measures 0 s
    vm["Main.actual"] = 0.5                                          # e drops by 0.5 in 0.1 s
    vm.run(cycles=1)
    # the derivative kick: 2 * (0.5 + 0.35 + 0.5 * (-0.5 / 0.1)) + 0.5 = -2.8, below Y_MIN
    assert vm["Main.fixed.Y"] == pytest.approx(0.0) and vm["Main.fixed.LIMITS_ACTIVE"] is True
    vm.run(cycles=1)       # the limited cycle did not integrate: 0.3 + 0.05 now
    assert vm["Main.fixed.Y"] == pytest.approx(2.0 * (0.5 + 0.35) + 0.5) and vm["Main.fixed.LIMITS_ACTIVE"] is False
    vm["Main.yMax"] = 1.0
    vm.run(cycles=1)
    assert vm["Main.fixed.Y"] == pytest.approx(1.0) and vm["Main.fixed.LIMITS_ACTIVE"] is True
    vm["Main.manual"] = True
    vm.run(cycles=1)
    assert vm["Main.fixed.Y"] == pytest.approx(7.0)
    vm["Main.manual"], vm["Main.reset"] = False, True
    vm.run(cycles=1)
    assert vm["Main.fixed.Y"] == pytest.approx(0.5) and vm["Main.fixed.LIMITS_ACTIVE"] is False
