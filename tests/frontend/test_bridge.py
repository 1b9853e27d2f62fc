"""The front-end bridge: snapshots between scans, writes at the start of the next scan, all or nothing."""

import threading

import pytest

import stvm
from stvm.frontend import VariableBridge, WriteRejected, catalog

SOURCE = """
TYPE Point : STRUCT x : REAL; y : REAL; END_STRUCT; END_TYPE
VAR_GLOBAL g_count : DINT; g_pts : ARRAY[1..3] OF Point; END_VAR
PROGRAM Main
VAR_INPUT run : BOOL; END_VAR
VAR n : INT; seen : DINT; timer : TON; END_VAR
VAR_EXTERNAL g_count : DINT; END_VAR
IF run THEN n := n + 1; END_IF;
seen := g_count;
timer(IN := run, PT := T#5ms);
END_PROGRAM
"""


@pytest.fixture
def vm(tmp_path):
    path = tmp_path / "main.st"
    path.write_text(SOURCE)
    return stvm.load([str(path)]).start(scan="1ms")


def test_snapshot_is_taken_between_scans(vm):
    bridge = VariableBridge(vm)
    watch = bridge.watch(["Main.n", "Main.run"])
    assert watch.latest() is None
    vm["Main.run"] = True
    vm.run(cycles=3)
    snap = watch.latest()
    assert (snap.scan, snap.now_ns, dict(snap.values)) == (2, 2_000_000, {"Main.n": 3, "Main.run": True})
    assert snap.version == 3


def test_watch_interval_limits_sampling(vm):
    bridge = VariableBridge(vm)
    seen = []
    bridge.watch(["Main.n"], every_ns=4_000_000, on_snapshot=seen.append)
    vm.run(cycles=10)
    assert [s.scan for s in seen] == [0, 4, 8]


def test_write_applies_at_start_of_next_scan(vm):
    bridge = VariableBridge(vm)
    watch = bridge.watch(["Main.seen"])
    future = bridge.submit({"g_count": 41})
    assert not future.done() and vm["g_count"] == 0   # nothing changes before the next scan
    vm.scan()
    assert future.result(timeout=0) is None
    assert watch.latest().values["Main.seen"] == 41   # the program saw the value in that scan


def test_bad_value_rejects_whole_batch(vm):
    bridge = VariableBridge(vm)
    with pytest.raises(WriteRejected) as err:
        bridge.submit({"Main.n": 5, "Main.run": "yes"})
    assert err.value.path == "Main.run"
    with pytest.raises(WriteRejected, match="out of range"):
        bridge.submit({"Main.n": 40000})
    with pytest.raises(WriteRejected, match="unknown variable"):
        bridge.submit({"Nope.x": 1})
    vm.scan()
    assert vm["Main.n"] == 0


def test_struct_member_in_array_written_from_another_thread(vm):
    bridge = VariableBridge(vm)
    results = []
    worker = threading.Thread(target=lambda: results.append(bridge.submit({"g_pts[2].y": 1.5})))
    worker.start()
    worker.join()
    vm.scan()
    results[0].result(timeout=1)
    assert vm["g_pts[2].y"] == 1.5
    assert bridge.format("g_pts[2].y", 1.5) == "1.5"


def test_pending_queue_is_bounded(vm):
    bridge = VariableBridge(vm, max_pending=2)
    bridge.submit({"Main.n": 1})
    bridge.submit({"Main.n": 2})
    with pytest.raises(WriteRejected, match="busy"):
        bridge.submit({"Main.n": 3})
    vm.scan()
    assert vm["Main.n"] == 2   # applied in order


def test_catalog_lists_programs_globals_and_members(vm):
    paths = {node.path: node for root in catalog(vm) for node in root.walk()}
    assert paths["Main"].kind == "program"
    assert paths["Main.run"].section == "VAR_INPUT"
    assert paths["g_pts[3].x"].kind == "member" and paths["g_pts[3].x"].leaf
    assert paths["Main.timer.Q"].in_fb
    assert "Main.g_count" not in paths            # externals are listed once, under the globals


def test_one_shot_sample_is_answered_at_the_end_of_the_next_scan(vm):
    bridge = VariableBridge(vm)
    vm["Main.run"] = True
    vm.run(cycles=2)
    future = bridge.sample(["Main.n", "g_pts[1].x"])
    assert not future.done()
    vm.scan()
    snap = future.result(timeout=0)
    assert (snap.scan, dict(snap.values)) == (2, {"Main.n": 3, "g_pts[1].x": 0.0})
    with pytest.raises(KeyError):
        bridge.sample(["Main.nope"])


def test_catalog_marks_constants(tmp_path):
    path = tmp_path / "c.st"
    path.write_text("VAR_GLOBAL CONSTANT LIMIT : INT := 5; END_VAR\nVAR_GLOBAL g : INT; END_VAR\n"
                    "PROGRAM Main VAR x : INT; END_VAR x := LIMIT; END_PROGRAM\n")
    vm = stvm.load([str(path)]).start()
    paths = {node.path: node for root in catalog(vm) for node in root.walk()}
    assert paths["LIMIT"].constant and not paths["g"].constant and not paths["Main.x"].constant


def test_changes_only_watch_hands_over_changed_samples_only(vm):
    bridge = VariableBridge(vm)
    seen = []
    bridge.watch(["Main.n", "g_count"], changes_only=True, on_snapshot=seen.append)
    vm.run(cycles=3)                      # nothing changes: one first sample only
    vm["Main.run"] = True
    vm.run(cycles=2)
    assert [(s.scan, s.values["Main.n"]) for s in seen] == [(0, 0), (3, 1), (4, 2)]


STRUCTS = """
TYPE Pose : STRUCT x : REAL; tag : STRING[8]; END_STRUCT; END_TYPE
VAR_GLOBAL poses : ARRAY[0..1] OF Pose; END_VAR
PROGRAM Main
VAR current : Pose; i : INT; END_VAR
VAR_EXTERNAL poses : ARRAY[0..1] OF Pose; END_VAR
current := poses[i];
i := 1 - i;
END_PROGRAM
"""


def test_watch_follows_struct_assignment(tmp_path):
    """A struct assigned as a whole is a new object: the sampler walks from the roots each time."""
    path = tmp_path / "s.st"
    path.write_text(STRUCTS)
    vm = stvm.load([str(path)]).start()
    vm["poses[0].x"], vm["poses[1].x"], vm["poses[1].tag"] = 1.5, 2.5, "b"
    bridge = VariableBridge(vm)
    watch = bridge.watch(["Main.current.x", "Main.current.tag", "poses[1].x"])
    vm.scan()
    assert watch.latest().values == {"Main.current.x": 1.5, "Main.current.tag": b"", "poses[1].x": 2.5}
    vm.scan()
    assert watch.latest().values == {"Main.current.x": 2.5, "Main.current.tag": b"b", "poses[1].x": 2.5}


def test_wall_clock_interval_limits_sampling_on_a_fast_virtual_clock(vm):
    bridge = VariableBridge(vm)
    seen = []
    bridge.watch(["Main.n"], every_wall_ns=3600 * 10**9, on_snapshot=seen.append)
    vm.run(cycles=50)   # 50 ms of VM time in far less than an hour of wall time
    assert [s.scan for s in seen] == [0]


def test_batch_submitted_after_an_earlier_one_was_applied_lands_in_a_later_scan(vm):
    # a momentary button: the release is sent once the press is applied; the program must see
    # the press in at least one scan even when both reach the bridge around the same scan start
    bridge = VariableBridge(vm)
    watch = bridge.watch(["Main.run"])
    seen = []
    watch.on_snapshot = lambda snap: seen.append(snap.values["Main.run"])
    press = bridge.submit({"Main.run": True})
    press.add_done_callback(lambda _: bridge.submit({"Main.run": False}))  # runs inside the apply
    vm.run(cycles=3)
    assert seen == [True, False, False]


def test_parse_reads_iec_literals_for_the_path_type(vm):
    bridge = VariableBridge(vm)
    assert bridge.parse("Main.run", "TRUE") is True
    assert bridge.parse("g_count", "16#FF") == 255
    assert bridge.parse("g_pts[2].x", "-1.5") == -1.5
    assert bridge.parse("Main.timer.PT", "T#1s500ms") == 1_500_000_000
    with pytest.raises(WriteRejected) as exc:
        bridge.parse("Main.n", "70000")
    assert exc.value.path == "Main.n" and "out of range" in exc.value.reason
    with pytest.raises(WriteRejected):
        bridge.parse("Main.nope", "1")
    with pytest.raises(WriteRejected):
        bridge.parse("Main.run", "maybe")


def test_the_write_hook_is_a_scan_start_hook_only_while_writes_wait(vm):
    bridge = VariableBridge(vm)
    assert bridge._apply_pending not in vm.on_scan_start        # no write: the scan start calls nothing
    first = bridge.submit({"g_count": 1})
    second = bridge.submit({"g_count": 2})
    assert vm.on_scan_start.count(bridge._apply_pending) == 1
    vm.scan()                                                  # applies both, then the scan end takes it out
    assert first.done() and second.done() and vm["Main.seen"] == 2
    assert bridge._apply_pending not in vm.on_scan_start
    third = bridge.submit({"g_count": 3})                      # armed again for the next scan
    assert not third.done() and vm["g_count"] == 2
    vm.scan()
    assert third.done() and vm["Main.seen"] == 3


def test_a_wall_clock_limited_watch_reads_the_clock_only_when_vm_time_may_have_caught_up(vm, monkeypatch):
    bridge = VariableBridge(vm)
    reads = []
    wall = [10_000_000_000]

    def monotonic_ns():
        reads.append(wall[0])
        return wall[0]
    monkeypatch.setattr("stvm.frontend.bridge.time.monotonic_ns", monotonic_ns)
    seen = []
    bridge.watch(["Main.n"], every_ns=2_000_000, every_wall_ns=20_000_000, on_snapshot=seen.append)
    vm.run(cycles=30)                # 30 ms of VM time, the wall clock stands still
    assert [s.scan for s in seen] == [0]
    # after the first refusal the next look is 20 ms of VM time later, not at every scan
    assert len(reads) <= 3
    wall[0] += 20_000_000
    vm.run(cycles=25)
    assert len(seen) == 2
