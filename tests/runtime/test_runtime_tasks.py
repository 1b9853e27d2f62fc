"""CONFIGURATION / RESOURCE / TASK: intervals, priorities, multi-rate scheduling, the default task."""

from __future__ import annotations

import pytest

from core_helpers import load_st, run_st, start_st

MS = 1_000_000

PROGRAMS = """
PROGRAM FastProg
VAR_EXTERNAL gSeq : DINT; gCount : DINT; END_VAR
VAR n : INT; END_VAR
n := n + 1; gCount := gCount + 2; gSeq := gSeq * 10 + 1;
END_PROGRAM
PROGRAM SlowProg
VAR_EXTERNAL gSeq : DINT; gCount : DINT; END_VAR
VAR n : INT; seen : DINT; END_VAR
n := n + 1; seen := gCount; gSeq := gSeq * 10 + 2;
END_PROGRAM
"""


def config(fast_ms: int, slow_ms: int, fast_prio: int, slow_prio: int) -> str:
    return f"""
CONFIGURATION Cfg
  VAR_GLOBAL gCount : DINT; gSeq : DINT; END_VAR
  RESOURCE Res ON PLC
    TASK Slow (INTERVAL := T#{slow_ms}ms, PRIORITY := {slow_prio});
    TASK Fast (INTERVAL := T#{fast_ms}ms, PRIORITY := {fast_prio});
    PROGRAM S WITH Slow : SlowProg;
    PROGRAM F WITH Fast : FastProg;
  END_RESOURCE
END_CONFIGURATION
"""


def test_multi_rate_tasks_run_at_integer_multiples():
    files = {"cfg.st": config(10, 30, 1, 5), "progs.st": PROGRAMS}
    vm = start_st(files, scan="1ms")           # the configuration's intervals decide, not --scan
    vm.run(cycles=7)                           # ticks 0..6 of 10 ms
    assert vm["F.n"] == 7
    assert vm["S.n"] == 3                      # ticks 0, 3, 6
    assert vm["S.seen"] == 14                  # at tick 6 Fast (priority 1) ran first
    assert vm.now_ns == 70 * MS


def test_base_period_is_the_gcd_of_intervals():
    files = {"cfg.st": config(10, 25, 1, 5), "progs.st": PROGRAMS}
    vm = start_st(files)
    vm.run(cycles=10)                          # base 5 ms: 50 ms of VM time
    assert vm.now_ns == 50 * MS
    assert vm["F.n"] == 5                      # 0, 10, 20, 30, 40 ms
    assert vm["S.n"] == 2                      # 0, 25 ms


@pytest.mark.parametrize(("fast_prio", "slow_prio", "first_tick_seq"), [(1, 5, 12), (5, 1, 21)])
def test_priority_orders_tasks_due_at_the_same_tick(fast_prio, slow_prio, first_tick_seq):
    files = {"cfg.st": config(10, 20, fast_prio, slow_prio), "progs.st": PROGRAMS}
    vm = start_st(files)
    vm.scan()
    assert vm["gSeq"] == first_tick_seq
    vm.scan()                                  # tick 1: only Fast
    assert vm["gSeq"] == first_tick_seq * 10 + 1


def test_two_instances_of_one_program_type_keep_separate_state():
    src = """
CONFIGURATION C
  RESOURCE R ON PLC
    TASK T (INTERVAL := T#5ms, PRIORITY := 1);
    PROGRAM A WITH T : Counter;
    PROGRAM B WITH T : Counter;
  END_RESOURCE
END_CONFIGURATION
PROGRAM Counter
VAR n : INT; END_VAR
n := n + 1;
END_PROGRAM
"""
    vm = start_st(src)
    vm.run(cycles=3)
    assert (vm["A.n"], vm["B.n"]) == (3, 3)
    vm["A.n"] = 100
    vm.scan()
    assert (vm["A.n"], vm["B.n"]) == (101, 4)


def test_lone_program_gets_default_task_at_scan_period():
    src = """
PROGRAM Main
VAR n : INT; t : TON; q : BOOL; END_VAR
n := n + 1;
t(IN := TRUE, PT := T#100ms);
q := t.Q;
END_PROGRAM
"""
    vm = start_st(src, scan="25ms")
    vm.run(cycles=4)                           # t = 0, 25, 50, 75 ms
    assert vm["Main.n"] == 4 and vm["Main.q"] is False
    assert vm.now_ns == 100 * MS
    vm.scan()                                  # t = 100 ms: ET = PT
    assert vm["Main.q"] is True
    assert len(vm.tasks) == 1 and vm.tasks[0].interval_ns == 25 * MS


def test_several_lone_programs_all_run_under_their_own_names():
    src = """
PROGRAM First VAR n : INT; END_VAR n := n + 1; END_PROGRAM
PROGRAM Second VAR n : INT; END_VAR n := n + 10; END_PROGRAM
"""
    out = run_st(src, cycles=3, prints=["First.n", "Second.n"])
    assert out == {"First.n": 3, "Second.n": 30}


def test_task_interval_and_priority_are_in_the_model():
    files = {"cfg.st": config(10, 30, 2, 7), "progs.st": PROGRAMS}
    project = load_st(files)
    tasks = {t.name.lower(): t for t in project.model.tasks}
    assert tasks["fast"].interval_ns == 10 * MS and tasks["fast"].priority == 2
    assert tasks["slow"].interval_ns == 30 * MS and tasks["slow"].priority == 7
