"""The Python API: stvm.load → Project.start → VM.scan/run, vm[path] get/set, the clock, the cache."""

from __future__ import annotations

import functools

import pytest

import stvm
from core_helpers import SYSMAC, load_st, start_st, write_st

# these tests are about Sysmac behaviour (ARRAY[*] from 0, STRING[n] with the NUL): its dialect
start_st = functools.partial(start_st, settings=SYSMAC)
load_st = functools.partial(load_st, settings=SYSMAC)

MS = 1_000_000

SOURCE = """
TYPE Pt : STRUCT x : INT; y : INT; END_STRUCT; Color : (Red, Green, Blue); END_TYPE
FUNCTION_BLOCK Doubler
VAR_INPUT i : INT; END_VAR
VAR_OUTPUT o : INT; END_VAR
o := i * 2;
END_FUNCTION_BLOCK
VAR_GLOBAL g : INT := 4; END_VAR
PROGRAM Main
VAR_EXTERNAL g : INT; END_VAR
VAR x : INT; first : INT; n : INT; p : Pt; arr : ARRAY[1..3] OF INT; m : ARRAY[0..1, 0..1] OF INT;
    d : Doubler; c : Color; s : STRING[8]; r : REAL; t : TIME; ps : ARRAY[1..2] OF Pt; b : BOOL; END_VAR
IF n = 0 THEN first := x; END_IF;
n := n + 1;
d(i := x + g);
END_PROGRAM
"""


@pytest.fixture(scope="module")
def project():
    return load_st(SOURCE)


def test_scan_and_run_advance_the_virtual_clock(project):
    vm = project.start(scan="10ms")
    assert vm.scan_count == 0 and vm.now_ns == 0
    vm.scan()
    assert vm.scan_count == 1 and vm.now_ns == 10 * MS
    vm.run(cycles=4)
    assert vm.scan_count == 5 and vm.now_ns == 50 * MS and vm["Main.n"] == 5
    vm.run(duration_ns=30 * MS)
    assert vm.scan_count == 8


def test_start_accepts_nanoseconds_and_iec_durations(project):
    assert project.start(scan=2 * MS).base_ns == 2 * MS
    assert project.start(scan="T#500us").base_ns == 500_000


def test_get_and_set_by_path(project):
    vm = project.start()
    vm["Main.x"] = 21                       # before the first scan
    vm["g"] = 100
    vm["Main.p.y"] = 7
    vm["Main.arr[2]"] = 9
    vm["Main.m[1, 0]"] = 3
    vm["Main.ps[2].x"] = 11
    vm["Main.c"] = "Color#Blue"
    vm["Main.s"] = "hi"
    vm["Main.r"] = 0.1
    vm["Main.t"] = 1500 * MS
    vm["Main.b"] = True
    vm.scan()
    assert vm["Main.first"] == 21
    assert vm["Main.d.o"] == 242
    assert vm["g"] == 100
    assert vm["Main.p.y"] == 7 and vm["Main.arr[2]"] == 9 and vm["Main.arr"] == [0, 9, 0]
    assert vm["Main.m[1,0]"] == 3 and vm["Main.ps[2].x"] == 11
    assert vm["Main.c"] == 2 and vm.format("Main.c") == "Color#Blue"
    assert vm["Main.s"] == b"hi"
    assert vm["Main.r"] == float.fromhex("0x1.99999ap-4")      # stored as float32
    assert vm.format("Main.t") == "T#1s500ms"
    assert vm["Main.b"] is True


def test_paths_are_case_insensitive(project):
    vm = project.start()
    vm["main.X"] = 3
    assert vm["MAIN.x"] == 3 and vm["Main.D.I"] == 0


@pytest.mark.parametrize("path", ["Nope.x", "Main.nope", "Main.arr[4]", "Main.arr[0]", "Main.p.z", "Main",
                                  "Main.x.y", "Main.arr[1,1]", ""])
def test_bad_paths_raise_key_errors(project, path):
    vm = project.start()
    with pytest.raises(KeyError):
        vm[path]


@pytest.mark.parametrize(("path", "value"), [("Main.x", 70000), ("Main.x", "abc"), ("Main.b", 5), ("Main.c", "Color#Pink"),
                                             ("Main.x", 1.5), ("Main.s", 3)])
def test_bad_values_raise_value_errors(project, path, value):
    vm = project.start()
    with pytest.raises(ValueError):
        vm[path] = value


def test_string_set_is_truncated_like_a_store(project):
    vm = project.start()
    vm["Main.s"] = "abcdefghijk"                 # STRING[8]: 7 bytes
    assert vm["Main.s"] == b"abcdefg"


def test_two_vms_of_one_project_are_independent(project):
    a, b = project.start(), project.start()
    a["Main.x"] = 5
    a.run(cycles=3)
    b.run(cycles=1)
    assert (a["Main.n"], b["Main.n"]) == (3, 1)
    assert b["Main.x"] == 0


def test_runs_are_bit_identical():
    src = """
PROGRAM Main
VAR r : REAL := 0.3; l : LREAL := 1.1; t : TON; et : TIME; n : DINT; END_VAR
r := r * 1.0001 + 0.7; l := l * 1.0000001 - 0.3;
t(IN := n MOD 50 < 40, PT := T#170ms); et := t.ET; n := n + 1;
END_PROGRAM"""
    project = load_st(src)

    def trace():
        vm = project.start(scan="7ms")
        out = []
        for _ in range(200):
            vm.scan()
            out.append((vm["Main.r"], vm["Main.l"], vm["Main.et"]))
        return out

    assert trace() == trace()


def test_load_error_carries_every_diagnostic():
    path = write_st("PROGRAM Main\nVAR x : INT; END_VAR\nx := y;\nx := 'a';\nEND_PROGRAM\n", "bad_api.st")
    with pytest.raises(stvm.LoadError) as info:
        stvm.load([path], use_cache=False)
    errors = [d for d in info.value.diagnostics if d.is_error]
    assert len(errors) == 2
    text = info.value.render()
    assert f"{path}:3:6: error:" in text and f"{path}:4:6: error:" in text


def test_cache_hit_gives_the_same_program(tmp_path, monkeypatch):
    monkeypatch.setenv("STVM_CACHE_DIR", str(tmp_path / "cache"))
    path = write_st("PROGRAM Main\nVAR x : INT; END_VAR\nx := x + 3;\nEND_PROGRAM\n", "cached.st")
    first = stvm.load([path])
    second = stvm.load([path])
    assert not first.from_cache and second.from_cache
    for p in (first, second):
        vm = p.start()
        vm.run(cycles=2)
        assert vm["Main.x"] == 6
    path.write_text("PROGRAM Main\nVAR x : INT; END_VAR\nx := x + 4;\nEND_PROGRAM\n")
    third = stvm.load([path])
    assert not third.from_cache                 # the key is the content, not the name
    vm = third.start()
    vm.scan()
    assert vm["Main.x"] == 4


def test_damaged_cache_entry_is_rebuilt(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("STVM_CACHE_DIR", str(cache))
    path = write_st("PROGRAM Main\nVAR x : INT; END_VAR\nx := 9;\nEND_PROGRAM\n", "damaged.st")
    stvm.load([path])
    for entry in cache.rglob("*"):
        if entry.is_file():
            entry.write_bytes(b"garbage")
    vm = stvm.load([path]).start()
    vm.scan()
    assert vm["Main.x"] == 9


def test_warnings_do_not_stop_a_load():
    vm = start_st("PROGRAM Main\nVAR s : STRING[3] := 'abcdef'; d : STRING := \"dq\"; END_VAR\nEND_PROGRAM\n")
    assert vm["Main.s"] == b"ab" and vm["Main.d"] == b"dq"
    assert len(vm.project.warnings) >= 2 and not any(w.is_error for w in vm.project.warnings)
