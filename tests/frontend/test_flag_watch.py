"""VariableBridge.watch_flags: details read only while their flag is TRUE, a one-scan flag never missed."""

from __future__ import annotations

import pytest

import stvm
from stvm.frontend import VariableBridge
from stvm.frontend.bridge import FlagWatch
from stvm.settings import Dialect, SysmacSettings

SOURCE = """
FUNCTION_BLOCK Axis
VAR_INPUT Fail : BOOL; Code : WORD; END_VAR
VAR_OUTPUT Error : BOOL; ErrorID : WORD; END_VAR
Error := Fail;
ErrorID := Code;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Cell
VAR A : Axis; END_VAR
VAR_INPUT Fail : BOOL; Code : WORD; END_VAR
A(Fail := Fail, Code := Code);
END_FUNCTION_BLOCK
VAR_GLOBAL Fail : ARRAY[1..3] OF BOOL; Code : ARRAY[1..3] OF WORD; Swap : BOOL; SpareFail : BOOL := TRUE; END_VAR
PROGRAM Main
VAR_EXTERNAL Fail : ARRAY[1..3] OF BOOL; Code : ARRAY[1..3] OF WORD; Swap : BOOL; SpareFail : BOOL; END_VAR
VAR C : Cell; B : ARRAY[1..2] OF Axis; Spare : ARRAY[1..2] OF Axis; END_VAR
C(Fail := Fail[1], Code := Code[1]);
B[1](Fail := Fail[2], Code := Code[2]);
B[2](Fail := Fail[3], Code := Code[3]);
Spare[1](Fail := SpareFail, Code := 16#0BAD);
IF Swap THEN B := Spare; Swap := FALSE; END_IF;
END_PROGRAM
"""

GROUPS = [("Main.C.A.Error", "Main.C.A.ErrorID"), ("Main.B[1].Error", "Main.B[1].ErrorID"),
          ("Main.B[2].Error", "Main.B[2].ErrorID")]


@pytest.fixture
def vm(tmp_path):
    path = tmp_path / "main.st"
    path.write_text(SOURCE)
    # TwinCAT: `B := Spare` copies an array of FB instances there (IEC and Sysmac refuse it)
    return stvm.load([str(path)], settings=SysmacSettings(dialect=Dialect.TWINCAT)).start(scan="1ms")


def watching(vm):
    seen = []
    watch = VariableBridge(vm).watch_flags(GROUPS, on_snapshot=seen.append)
    assert isinstance(watch, FlagWatch) and watch._signals is not None   # the compiled probe, not the fallback
    return watch, seen


def test_first_scan_makes_one_snapshot_then_nothing_while_flags_stay_false(vm):
    watch, seen = watching(vm)
    vm.run(cycles=5)
    assert [s.scan for s in seen] == [0]
    assert dict(seen[0].values) == {p: (False if p.endswith("Error") else 0) for g in GROUPS for p in g}


def test_a_detail_changing_while_its_flag_is_false_makes_no_snapshot(vm):
    watch, seen = watching(vm)
    vm.run(cycles=1)
    vm["Code[1]"] = 7
    vm.run(cycles=3)
    assert len(seen) == 1


def test_a_flag_true_for_one_scan_is_seen_at_that_scan_with_its_details(vm):
    watch, seen = watching(vm)
    vm.run(cycles=2)
    vm["Fail[2]"], vm["Code[2]"] = True, 0x42
    vm.run(cycles=1)                       # scan 2: B[1].Error TRUE
    vm["Fail[2]"] = False
    vm.run(cycles=2)                       # scan 3: FALSE again
    assert [(s.scan, s.now_ns, s.values["Main.B[1].Error"], s.values["Main.B[1].ErrorID"]) for s in seen] == \
        [(0, 0, False, 0), (2, 2_000_000, True, 0x42), (3, 3_000_000, False, 0x42)]


def test_details_are_followed_while_the_flag_is_true(vm):
    watch, seen = watching(vm)
    vm["Fail[1]"], vm["Code[1]"] = True, 1
    vm.run(cycles=2)
    vm["Code[1]"] = 2
    vm.run(cycles=2)
    vm["Fail[3]"], vm["Code[3]"] = True, 3   # a second flag while the first is TRUE
    vm.run(cycles=1)
    vm["Code[1]"] = 4
    vm.run(cycles=1)
    assert [(s.scan, s.values["Main.C.A.ErrorID"], s.values["Main.B[2].Error"]) for s in seen] == \
        [(0, 1, False), (2, 2, False), (4, 2, True), (5, 4, True)]
    vm["Fail[1]"] = vm["Fail[3]"] = False
    vm.run(cycles=2)
    assert [s.scan for s in seen][-1] == 6 and not seen[-1].values["Main.C.A.Error"]
    # the set of TRUE flags seen before compiles nothing new
    assert set(watch._probes) == {(), (0,), (0, 2)}


def test_an_array_of_fb_instances_assigned_as_a_whole_is_followed(vm):
    watch, seen = watching(vm)
    vm.run(cycles=1)
    vm["Swap"] = True                      # B := Spare: the array's elements are copies now
    vm.run(cycles=1)
    assert seen[-1].scan == 1 and seen[-1].values["Main.B[1].ErrorID"] == 0x0BAD
    vm["SpareFail"] = False                # B[1] is another object now: the probe reaches it by its index
    vm.run(cycles=1)
    assert seen[-1].scan == 2 and not seen[-1].values["Main.B[1].Error"]


def test_a_path_through_a_var_in_out_falls_back_to_an_ordinary_changes_only_watch(tmp_path):
    path = tmp_path / "main.st"
    path.write_text("""
FUNCTION_BLOCK Holder
VAR_IN_OUT Flag : BOOL; END_VAR
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : BOOL; h : Holder; n : INT; END_VAR
h(Flag := f);
n := n + 1;
END_PROGRAM
""")
    vm = stvm.load([str(path)]).start(scan="1ms")
    vm.run(cycles=1)                       # the in-out bound
    seen = []
    watch = VariableBridge(vm).watch_flags([("Main.h.Flag", "Main.n")], on_snapshot=seen.append)
    assert watch._signals is None
    vm.run(cycles=3)
    assert [s.scan for s in seen] == [1, 2, 3]   # every change, as `changes_only`
