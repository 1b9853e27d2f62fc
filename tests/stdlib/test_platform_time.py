"""Clock pieces of Tc2_System / Tc2_Utilities (`--dialect twincat`): F_GetSystemTime and
FB_LocalSystemTime read the virtual date and time (the run's start DT plus the virtual clock)."""

from __future__ import annotations

import datetime as dt

from stvm.project import load
from stvm.settings import DEFAULT_SETTINGS
from stvm.stdlib.tc2_system import FILETIME_1970
from tests.core_helpers import write_files

TWINCAT = DEFAULT_SETTINGS.with_table({"dialect": "twincat"}, "test")

SOURCE = """
PROGRAM Main
VAR
    fbTime : FB_LocalSystemTime := (bEnable := TRUE, dwCycle := 1);
    stamp : ULINT;
    now : TIMESTRUCT;
    valid : BOOL;
    tz : E_TimeZoneID;
    enable : BOOL := TRUE;
    text : STRING(24);
END_VAR
fbTime(bEnable := enable);
now := fbTime.systemTime;
valid := fbTime.bValid;
tz := fbTime.tzID;
stamp := F_GetSystemTime();
text := SYSTEMTIME_TO_STRING(now);
END_PROGRAM
"""

START = dt.datetime(2024, 3, 3, 23, 59, 59)      # a Sunday


def _vm():
    start_ns = int((START - dt.datetime(1970, 1, 1)).total_seconds()) * 1_000_000_000
    return load(write_files({"main.st": SOURCE}), TWINCAT, use_cache=False).start(scan="250ms", start_dt_ns=start_ns)


def test_local_system_time_follows_the_virtual_clock() -> None:
    vm = _vm()
    vm.run(cycles=1)
    fields = ("wYear", "wMonth", "wDay", "wDayOfWeek", "wHour", "wMinute", "wSecond", "wMilliseconds")
    got = {name: vm[f"Main.now.{name}"] for name in fields}
    assert got == {"wYear": 2024, "wMonth": 3, "wDay": 3, "wDayOfWeek": 0, "wHour": 23, "wMinute": 59,
                   "wSecond": 59, "wMilliseconds": 0}
    assert vm["Main.valid"] is True
    vm.run(cycles=5)       # the sixth scan starts 1.25 s later: past midnight into Monday
    got = {name: vm[f"Main.now.{name}"] for name in fields}
    assert got == {"wYear": 2024, "wMonth": 3, "wDay": 4, "wDayOfWeek": 1, "wHour": 0, "wMinute": 0,
                   "wSecond": 0, "wMilliseconds": 250}
    # Beckhoff Infosys "SYSTEMTIME_TO_STRING": YYYY-MM-DD-hh:mm:ss.xxx
    assert vm["Main.text"] == b"2024-03-04-00:00:00.250"


def test_disabled_it_is_not_valid() -> None:
    vm = _vm()
    vm["Main.enable"] = False
    vm.run(cycles=1)
    assert vm["Main.valid"] is False
    assert vm["Main.now.wYear"] == 0


def test_system_time_counts_100ns_from_1601() -> None:
    vm = _vm()
    vm.run(cycles=2)
    seconds = (START - dt.datetime(1970, 1, 1)).total_seconds() + 0.25
    assert vm["Main.stamp"] == int(seconds * 10_000_000) + FILETIME_1970
    # the same instant seen from 1601: 2024-03-03 23:59:59.25 UTC
    assert dt.datetime(1601, 1, 1) + dt.timedelta(microseconds=vm["Main.stamp"] // 10) == \
        START + dt.timedelta(milliseconds=250)


TASK_INFO = """
PROGRAM Main
VAR
    i : BYTE;
    bare, listed : UDINT;
    first : BOOL;
END_VAR
i := GETCURTASKINDEXEX();
bare := _TaskInfo[GETCURTASKINDEXEX()].CycleCount;
listed := TwinCAT_SystemInfoVarList._TaskInfo[i].CycleCount;
first := _TaskInfo[i].FirstCycle;
END_PROGRAM
"""


def test_task_info_is_reached_bare_and_through_its_list() -> None:
    vm = load(write_files({"main.st": TASK_INFO}), TWINCAT, use_cache=False).start(scan="10ms")
    vm.run(cycles=1)
    assert (vm["Main.i"], vm["Main.bare"], vm["Main.first"]) == (1, 0, True)
    vm.run(cycles=2)
    assert (vm["Main.bare"], vm["Main.listed"], vm["Main.first"]) == (2, 2, False)
