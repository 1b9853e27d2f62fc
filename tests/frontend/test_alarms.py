"""stvm/frontend/alarms.py: FB Error outputs and a VM fault as alarms (raise, update, return, ack)."""

from __future__ import annotations

from pathlib import Path

import pytest

import stvm
from stvm.frontend import VariableBridge
from stvm.frontend.alarms import AlarmList, find_sources

SOURCE = """
FUNCTION_BLOCK Axis
VAR_INPUT Fail : BOOL; Code : WORD; END_VAR
VAR_OUTPUT Busy : BOOL; Error : BOOL; ErrorID : WORD; ErrorDescrip : STRING[50]; END_VAR
Error := Fail;
IF Fail THEN ErrorID := Code; ErrorDescrip := 'Axis fault'; ELSE ErrorID := 0; ErrorDescrip := ''; END_IF;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Quiet
VAR_OUTPUT Done : BOOL; END_VAR
Done := TRUE;
END_FUNCTION_BLOCK
VAR_GLOBAL FailA : BOOL; CodeA : WORD := 16#0101; Div : INT := 1; END_VAR
PROGRAM Main
VAR_EXTERNAL FailA : BOOL; CodeA : WORD; Div : INT; END_VAR
VAR A : Axis; B : ARRAY[1..2] OF Axis; Q : Quiet; x : INT; END_VAR
A(Fail := FailA, Code := CodeA);
B[1](Fail := FALSE);
B[2](Fail := FALSE);
Q();
x := 10 / Div;
END_PROGRAM
"""


@pytest.fixture
def project(tmp_path: Path):
    (tmp_path / "main.st").write_text(SOURCE)
    (tmp_path / "stvm.toml").write_text('[project]\nfiles = ["main.st"]\n')
    return stvm.load([str(tmp_path / "main.st")])


class Clock:
    now = 1_800_000_000.0

    def __call__(self):
        return self.now


def test_every_instance_with_an_error_output_is_a_source(project):
    vm = project.start(scan="1ms")
    sources = {s.path: s for s in find_sources(vm)}
    assert set(sources) == {"Main.A", "Main.B[1]", "Main.B[2]"}   # Quiet has no Error
    assert sources["Main.A"].code == "Main.A.ErrorID"
    assert sources["Main.A"].text == "Main.A.ErrorDescrip"
    assert sources["Main.A"].fb_type.lower() == "axis"
    vm.close()


def test_rise_update_return_and_acknowledge(project):
    vm = project.start(scan="1ms")
    bridge = VariableBridge(vm)
    clock = Clock()
    alarms = AlarmList.attach(bridge, clock)
    seen = []
    alarms.subscribe(seen.append)
    vm.run(cycles=3)
    assert alarms.current() == []

    vm["FailA"] = True
    vm.run(cycles=2)
    [alarm] = alarms.current()
    assert (alarm.source, alarm.code, alarm.text, alarm.active, alarm.acknowledged) == \
        ("Main.A", 0x0101, "Axis fault", True, False)
    assert alarm.raised_at == clock.now and alarm.as_json()["code_text"] == "16#0101"

    vm["CodeA"] = 0x0202                     # same alarm, new code
    vm.run(cycles=1)
    [updated] = alarms.current()
    assert (updated.id, updated.code) == (alarm.id, 0x0202)

    vm["FailA"] = False                      # returned: listed until acknowledged
    vm.run(cycles=1)
    [returned] = alarms.current()
    assert (returned.active, returned.acknowledged) == (False, False)
    assert alarms.acknowledge(returned.id).acknowledged
    assert alarms.current() == []
    assert [a.id for a in alarms.history()] == [alarm.id]
    assert len(seen) == 4                    # raise, code change, return, acknowledge
    vm.close()


def test_an_acknowledged_active_alarm_stays_until_it_returns(project):
    vm = project.start(scan="1ms")
    alarms = AlarmList.attach(VariableBridge(vm))
    vm["FailA"] = True
    vm.run(cycles=1)
    [alarm] = alarms.current()
    assert alarms.acknowledge(alarm.id).active
    assert alarms.acknowledge(99999) is None
    assert alarms.current()[0].acknowledged
    vm["FailA"] = False
    vm.run(cycles=1)
    assert alarms.current() == []
    vm["FailA"] = True                       # a new rising edge is a new alarm
    vm.run(cycles=1)
    assert alarms.current()[0].id == alarm.id + 1
    vm.close()


def test_a_vm_fault_is_an_alarm(project):
    vm = project.start(scan="1ms")
    alarms = AlarmList.attach(VariableBridge(vm))
    vm["Div"] = 0
    with pytest.raises(Exception):
        vm.run(cycles=2)
    alarm = alarms.poll_vm()
    assert alarm is not None and alarm.source == "VM" and alarm.severity == 1000
    assert "division" in alarm.text.lower() or "zero" in alarm.text.lower()
    assert alarms.poll_vm() is None          # raised once
    vm.close()
