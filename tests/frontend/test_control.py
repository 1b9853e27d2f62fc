"""Run control: a VM paused, resumed and stepped from another thread, between whole scans."""

import threading

import pytest

import stvm
from stvm.frontend import RunControl, VariableBridge
from stvm.runtime.watchdog import Watchdog

SOURCE = """
VAR_GLOBAL g_set : DINT; END_VAR
PROGRAM Main
VAR_EXTERNAL g_set : DINT; END_VAR
VAR n : DINT; seen : DINT; END_VAR
n := n + 1;
seen := g_set;
END_PROGRAM
"""


@pytest.fixture
def vm(tmp_path):
    path = tmp_path / "main.st"
    path.write_text(SOURCE)
    return stvm.load([str(path)]).start(scan="1ms")


def run_in_thread(vm, cycles):
    """The scan loop in its own thread, as `stvm run` runs it beside a front end."""
    errors = []

    def loop():
        try:
            vm.run(cycles=cycles)
        except BaseException as exc:   # noqa: BLE001 - the test asserts on it
            errors.append(exc)
    thread = threading.Thread(target=loop, daemon=True)
    thread.start()
    return thread, errors


def test_step_runs_exact_scans_and_waits(vm):
    bridge = VariableBridge(vm)
    control = RunControl(vm)
    watch = bridge.watch(["Main.n"])
    control.pause()
    thread, errors = run_in_thread(vm, cycles=1000)
    assert control.wait_paused(5)
    assert vm.scan_count == 0 and watch.latest() is None
    assert control.step(3).result(5) == 3
    assert vm["Main.n"] == 3 and watch.latest().values == {"Main.n": 3}
    assert control.step(2).result(5) == 5
    assert watch.latest().scan == 4 and watch.latest().now_ns == 4_000_000   # deterministic VM time
    control.resume()
    thread.join(5)
    assert not errors and vm.scan_count == 1000


def test_paused_vm_answers_reads_and_applies_writes(vm):
    bridge = VariableBridge(vm)
    control = RunControl(vm)
    control.pause()
    thread, errors = run_in_thread(vm, cycles=10)
    assert control.wait_paused(5)
    control.step(2).result(5)
    snap = bridge.sample(["Main.n", "g_set"]).result(5)     # answered while paused
    assert (snap.scan, snap.now_ns, dict(snap.values)) == (1, 1_000_000, {"Main.n": 2, "g_set": 0})
    bridge.submit({"g_set": 7}).result(5)                     # applied while paused
    assert bridge.sample(["g_set", "Main.seen"]).result(5).values == {"g_set": 7, "Main.seen": 0}
    control.step(1).result(5)
    assert bridge.sample(["Main.seen"]).result(5).values == {"Main.seen": 7}
    control.close()
    thread.join(5)
    assert not errors and vm.scan_count == 10


def test_pause_is_not_a_watchdog_fault(vm):
    control = RunControl(vm, poll_s=0.01)
    control.pause()
    errors = []

    def loop():
        try:
            with Watchdog(vm, 0.2):
                vm.run(cycles=3)
        except BaseException as exc:   # noqa: BLE001
            errors.append(exc)
    thread = threading.Thread(target=loop, daemon=True)
    thread.start()
    assert control.wait_paused(5)
    threading.Event().wait(0.8)        # four watchdog limits
    control.resume()
    thread.join(5)
    assert not errors and vm.scan_count == 3 and vm.fault is None


def test_pause_cancels_a_step_and_bad_counts_are_refused(vm):
    control = RunControl(vm)
    with pytest.raises(ValueError):
        control.step(0)
    future = control.step(100)
    control.pause()
    with pytest.raises(RuntimeError, match="cancelled"):
        future.result(1)


def test_realtime_run_has_no_run_control(tmp_path):
    path = tmp_path / "main.st"
    path.write_text(SOURCE)
    vm = stvm.load([str(path)]).start(scan="1ms", realtime=True)
    with pytest.raises(ValueError, match="virtual clock"):
        RunControl(vm)


def test_free_running_vm_is_not_held(vm):
    control = RunControl(vm)
    vm.run(cycles=5)
    assert vm.scan_count == 5 and not control.paused
