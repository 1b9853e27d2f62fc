"""CODESYS V3 operators beyond IEC's (stvm/stdlib/cds_operators.*: TIME(), TRUNC_INT and the
date/time conversions TOD_TO_TIME, TIME_TO_TOD, DATE_TO_DT) under `--dialect codesys` and
`--dialect twincat`, and the Tc3_Module / type-system pieces of TwinCAT (HRESULT, SUCCEEDED,
FAILED, TcEventSeverity, T_AmsNetIdArr)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from stvm.project import LoadError, load
from stvm.settings import DEFAULT_SETTINGS
from stvm.stdlib.cds_operators import BOOT_MS
from tests.core_helpers import write_files

TWINCAT = DEFAULT_SETTINGS.with_table({"dialect": "twincat"}, "test")
CODESYS = DEFAULT_SETTINGS.with_table({"dialect": "codesys"}, "test")
MS = 1_000_000

OPERATORS = """
PROGRAM Main
VAR
    t : TIME;
    i1, i2, i3 : INT;
    since : TIME;
    tod1, tod2 : TOD;
    d : DT;
END_VAR
t := TIME();
i1 := TRUNC_INT(1.9);
i2 := TRUNC_INT(-1.4);
i3 := TRUNC_INT(40000.0);
since := TOD_TO_TIME(TOD#10:30:15.5);
tod1 := TIME_TO_TOD(T#1h2m3s);
tod2 := TIME_TO_TOD(T#25h);
d := DATE_TO_DT(D#2024-03-01);
END_PROGRAM
"""


@pytest.mark.parametrize("settings", [TWINCAT, CODESYS], ids=["twincat", "codesys"])
def test_operators_of_codesys(settings) -> None:
    vm = load(write_files({"main.st": OPERATORS}), settings, use_cache=False).start(scan="10ms")
    vm.run(cycles=3)       # the third scan starts at 20 ms of the virtual clock
    assert vm["Main.t"] == (20 + BOOT_MS) * MS
    # CODESYS help, "TRUNC_INT": 1.9 -> 1, -1.4 -> -1; a value beyond INT wraps (stvm's choice)
    assert (vm["Main.i1"], vm["Main.i2"], vm["Main.i3"]) == (1, -1, 40000 - 65536)
    assert vm["Main.since"] == ((10 * 60 + 30) * 60 * 1000 + 15500) * MS
    assert vm["Main.tod1"] == 3723 * 1000 * MS
    assert vm["Main.tod2"] == 3600 * 1000 * MS       # a day and an hour: one hour after midnight
    load_dt = load(write_files({"main.st": "PROGRAM Main\nVAR d : DT; END_VAR\nd := DT#2024-03-01-00:00:00;\nEND_PROGRAM\n"}),
                   settings, use_cache=False).start()
    load_dt.run(cycles=1)
    assert vm["Main.d"] == load_dt["Main.d"]


def test_time_wraps_after_32_bits_of_milliseconds() -> None:
    from stvm.stdlib.cds_operators import time_since_start
    ctx = SimpleNamespace(now_ns=((1 << 32) - BOOT_MS + 5) * MS)    # 5 ms past the overflow
    assert time_since_start(ctx) == 5 * MS


def test_the_operators_are_not_iec() -> None:
    with pytest.raises(LoadError) as info:
        load(write_files({"main.st": OPERATORS}), DEFAULT_SETTINGS, use_cache=False)
    assert "TRUNC_INT" in info.value.render()


TC3 = """
PROGRAM Main
VAR
    hrBad : HRESULT := -16#7FFF0000;
    hrInfo : HRESULT := 1;
    okBad, failBad, okInfo, failInfo : BOOL;
    sev : TcEventSeverity := TcEventSeverity.Warning;
    n : INT;
    net : T_AmsNetIdArr := [127, 16, 17, 3, 1, 1];
    b0 : BYTE;
    text, longest : T_AmsNetID;
    top : T_AmsNetIdArr := [255, 255, 255, 255, 255, 255];
END_VAR
okBad := SUCCEEDED(hrBad);
failBad := FAILED(hrBad);
okInfo := SUCCEEDED(hrInfo);
failInfo := FAILED(hr := hrInfo);
n := TO_INT(sev) + TO_INT(TcEventSeverity.Critical) * 10;
b0 := net[0];
text := F_CreateAmsNetId(net);
longest := F_CreateAmsNetId(nIds := top);
END_PROGRAM
"""


def test_hresult_and_event_severity() -> None:
    vm = load(write_files({"main.st": TC3}), TWINCAT, use_cache=False).start()
    vm.run(cycles=1)
    assert (vm["Main.okBad"], vm["Main.failBad"]) == (False, True)
    assert (vm["Main.okInfo"], vm["Main.failInfo"]) == (True, False)   # a positive HRESULT is a message, no error
    assert vm["Main.n"] == 2 + 40           # Beckhoff: Warning 2, Critical 4
    assert vm["Main.b0"] == 127
    # Beckhoff Infosys "F_CreateAmsNetId": [127, 16, 17, 3, 1, 1] -> '127.16.17.3.1.1'
    assert vm["Main.text"] == b"127.16.17.3.1.1"
    assert vm["Main.longest"] == b"255.255.255.255.255.255"     # 23 characters: T_AmsNetID holds it


POWERS = """
PROGRAM Main
VAR
    fPow : LREAL;
    nBase : INT := 2;
    nExponent : INT := 7;
    literal : LREAL;
    r : REAL;
END_VAR
fPow := EXPT(nBase, nExponent);
literal := EXPT(7, 2);
r := EXPT(REAL#1.5, 2);
END_PROGRAM
"""


@pytest.mark.parametrize("settings", [TWINCAT, CODESYS], ids=["twincat", "codesys"])
def test_expt_of_an_integer_base(settings) -> None:
    # CODESYS help and Beckhoff Infosys "EXPT": any numeric base, EXPT(7, 2) = 49, 2 ** 7 = 128
    vm = load(write_files({"main.st": POWERS}), settings, use_cache=False).start()
    vm.run(cycles=1)
    assert (vm["Main.fPow"], vm["Main.literal"], vm["Main.r"]) == (128.0, 49.0, 2.25)


def test_iec_keeps_expt_to_a_real_base() -> None:
    with pytest.raises(LoadError) as info:
        load(write_files({"main.st": POWERS}), DEFAULT_SETTINGS, use_cache=False)
    assert "EXPT" in info.value.render()


OWN_ROUND = """
FUNCTION ROUND : REAL
VAR_INPUT
    in : REAL;
    N : INT;
END_VAR
ROUND := TRUNC_INT(in * 10.0) / 10.0;
END_FUNCTION

PROGRAM Main
VAR
    r : REAL;
END_VAR
r := ROUND(1.26, 1);
END_PROGRAM
"""


@pytest.mark.parametrize("settings", [TWINCAT, CODESYS], ids=["twincat", "codesys"])
def test_a_project_declares_its_own_round(settings) -> None:
    # Omron's Round/RoundUp are not TwinCAT or CODESYS functions; OSCAT BASIC declares ROUND
    vm = load(write_files({"main.st": OWN_ROUND}), settings, use_cache=False).start()
    vm.run(cycles=1)
    assert vm["Main.r"] == pytest.approx(1.2)
