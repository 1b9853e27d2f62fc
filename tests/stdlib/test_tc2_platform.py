"""The Beckhoff platform libraries under `--dialect twincat` (stvm/stdlib/tc2_system.*,
tc2_utilities.st, the Tc2_Standard input names): ADS log messages, the CPU counter on the
virtual clock, the task index, trimming and hexadecimal text, CONCAT(STR1 :=, STR2 :=)."""

from __future__ import annotations

import pytest

from stvm.project import LoadError, load
from stvm.settings import DEFAULT_SETTINGS
from stvm.stdlib.tc2_system import severity
from tests.core_helpers import cli, write_files

TWINCAT = DEFAULT_SETTINGS.with_table({"dialect": "twincat"}, "test")

SOURCE = """
PROGRAM Main
VAR
    rc : DINT;
    counter : GETCPUCOUNTER;
    task : GETCURTASKINDEX;
    lo, hi : UDINT;
    idx : BYTE;
    trimmed : T_MaxString;
    joined : T_MaxString;
    found : INT;
    hex1, hex2, hex3, hex4, hex5 : T_MaxString;
    n : UINT;
    piece : T_MaxString;
END_VAR
rc := ADSLOGSTR(msgCtrlMask := ADSLOG_MSGTYPE_ERROR OR ADSLOG_MSGTYPE_STRING, msgFmtStr := 'Test %s failed',
                strArg := 'one');
ADSLOGDINT(msgCtrlMask := ADSLOG_MSGTYPE_HINT, msgFmtStr := 'count %d', dintArg := -42);
ADSLOGLREAL(msgCtrlMask := ADSLOG_MSGTYPE_WARN, msgFmtStr := 'took %f s', lrealArg := 0.25);
counter();
lo := counter.cpuCntLoDW;
hi := counter.cpuCntHiDW;
task();
idx := task.index;
trimmed := F_LTrim(in := F_RTrim(in := '  name of test   '));
joined := CONCAT(STR1 := 'Test', STR2 := 'Suite');
n := LEN(STR := joined);
piece := MID(STR := joined, LEN := 3, POS := 2);
found := FIND(STR1 := joined, STR2 := 'Suite');
hex1 := BYTE_TO_HEXSTR(in := 16#0A, iPrecision := 2, bLoCase := FALSE);
hex2 := BYTE_TO_HEXSTR(in := 16#AB, iPrecision := 0, bLoCase := TRUE);
hex3 := DWORD_TO_HEXSTR(in := 16#1F, iPrecision := 8, bLoCase := FALSE);
hex4 := LWORD_TO_HEXSTR(in := 16#DEADBEEF00, iPrecision := 0, bLoCase := FALSE);
hex5 := WORD_TO_HEXSTR(in := 0, iPrecision := 0, bLoCase := FALSE);
END_PROGRAM
"""


def _vm():
    return load(write_files({"main.st": SOURCE}), TWINCAT, use_cache=False).start(scan="10ms")


def test_ads_log_messages_reach_the_sink_with_their_argument() -> None:
    vm = _vm()
    log: list[tuple[int, str]] = []
    vm.ctx.ads_log = lambda mask, text: log.append((mask, text))
    vm.run(cycles=1)
    assert log == [(0x84, "Test one failed"), (0x01, "count -42"), (0x02, "took 0.250000 s")]
    assert vm["Main.rc"] == 0
    assert [severity(mask) for mask, _ in log] == ["error", "hint", "warning"]


def test_without_a_sink_messages_print_one_line_each(tmp_path) -> None:
    path = write_files({"main.st": SOURCE})[0]
    rc, out, err = cli(["run", "--dialect", "twincat", "--cycles", "1", path])
    assert rc == 0, err
    assert out.splitlines()[:3] == ["error: Test one failed", "hint: count -42", "warning: took 0.250000 s"]


def test_the_cpu_counter_is_the_virtual_clock_in_100ns_ticks() -> None:
    from stvm.stdlib.tc2_system import CpuCounter
    vm = _vm()
    vm.ctx.ads_log = lambda mask, text: None
    vm.run(cycles=3)       # the third scan starts at 20 ms; the counter never reads 0 (TcUnit: "not started")
    assert (vm["Main.hi"] << 32) + vm["Main.lo"] == 20_000_000 // 100 + CpuCounter.BOOT_TICKS
    assert vm["Main.idx"] == 1


def test_utilities_and_standard_input_names() -> None:
    vm = _vm()
    vm.ctx.ads_log = lambda mask, text: None
    vm.run(cycles=1)
    text = {k: vm[f"Main.{k}"] for k in ("trimmed", "joined", "piece", "hex1", "hex2", "hex3", "hex4", "hex5")}
    assert text == {"trimmed": b"name of test", "joined": b"TestSuite", "piece": b"est",
                    "hex1": b"0A", "hex2": b"ab", "hex3": b"0000001F", "hex4": b"DEADBEEF00", "hex5": b"0"}
    assert vm["Main.n"] == 9 and vm["Main.found"] == 5


def test_the_platform_libraries_exist_only_under_twincat() -> None:
    with pytest.raises(LoadError) as info:
        load(write_files({"main.st": SOURCE}), DEFAULT_SETTINGS, use_cache=False)
    assert "ADSLOGSTR" in info.value.render()


def test_type_classes_are_reached_through_their_namespaces() -> None:
    src = """
PROGRAM Main
VAR
    a : IBaseLibrary.TypeClass := IBaseLibrary.TypeClass.TYPE_LREAL;
    b : __SYSTEM.TYPE_CLASS;
    n : INT;
    w : INT;
END_VAR
w := WLEN(STR := "héllo");
b := __SYSTEM.TYPE_CLASS.TYPE_STRING;
n := TO_INT(b);
CASE a OF
    IBaseLibrary.TypeClass.TYPE_LREAL: n := n + 100;
END_CASE
END_PROGRAM
"""
    vm = load(write_files({"main.st": src}), TWINCAT, use_cache=False).start()
    vm.run(cycles=1)
    assert vm["Main.n"] == 116
    assert vm["Main.w"] == 5     # WLEN (Tc2_Standard) counts characters of a WSTRING


def test_an_enumeration_compares_with_an_integer_under_twincat() -> None:
    src = """
PROGRAM Main
VAR
    cls : __SYSTEM.TYPE_CLASS := __SYSTEM.TYPE_CLASS.TYPE_INT;
    code : UDINT := 7;
    same, other : BOOL;
END_VAR
same := UDINT_TO_INT(code) = IBaseLibrary.TypeClass.TYPE_INT;
other := cls <> 8;
END_PROGRAM
"""
    vm = load(write_files({"main.st": src}), TWINCAT, use_cache=False).start()
    vm.run(cycles=1)
    assert vm["Main.same"] is True and vm["Main.other"] is True


def test_the_system_info_list_counts_each_tasks_cycles() -> None:
    src = """
PROGRAM Main
VAR
    taskIdx : GETCURTASKINDEX;
    count : UDINT;
    first : BOOL;
    firstSeen : INT;
    name : STRING;
    period : UDINT;
END_VAR
taskIdx();
count := TwinCAT_SystemInfoVarList._TaskInfo[taskIdx.index].CycleCount;
first := TwinCAT_SystemInfoVarList._TaskInfo[taskIdx.index].FirstCycle;
IF first THEN firstSeen := firstSeen + 1; END_IF
name := TwinCAT_SystemInfoVarList._AppInfo.ProjectName;
period := TwinCAT_SystemInfoVarList._TaskInfo[1].CycleTime;
END_PROGRAM
"""
    paths = write_files({"main.st": src})
    vm = load(paths, TWINCAT, use_cache=False).start(scan="10ms")
    vm.run(cycles=4)
    assert vm["Main.count"] == 3 and vm["Main.first"] is False and vm["Main.firstSeen"] == 1
    assert vm["Main.period"] == 100_000     # 10 ms in 100 ns units
    assert vm["Main.name"] == b"stvm"       # no manifest: no project name
