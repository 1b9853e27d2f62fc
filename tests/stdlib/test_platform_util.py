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
