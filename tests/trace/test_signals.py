"""Watch patterns: globs over program variables, FB members, struct fields, array elements."""

from __future__ import annotations

from pathlib import Path

import pytest

from stvm.trace.signals import WatchError, compile_pattern, make_sampler, select_signals

COUNTER = Path(__file__).parent / "st" / "counter.st"


@pytest.fixture(scope="module")
def vm():
    from stvm.project import load
    return load([COUNTER]).start(scan="1ms")


def names(vm, *patterns):
    return [s.name for s in select_signals(vm, list(patterns))]


def test_star_is_one_level_and_aggregates_expand(vm):
    got = names(vm, "Main.*")
    assert got[:3] == ["Main.counter", "Main.flag", "Main.arr[0]"]
    assert "Main.pair.a" in got and "Main.pairs[2].b" in got and "Main.t.Q" in got and "Main.txt" in got


def test_array_index_glob_and_struct_field(vm):
    assert names(vm, "Main.arr[*]") == [f"Main.arr[{i}]" for i in range(4)]
    assert names(vm, "Main.pairs[*].b") == ["Main.pairs[1].b", "Main.pairs[2].b"]
    assert names(vm, "Main.arr[1*]") == ["Main.arr[1]"]


def test_double_star_crosses_levels(vm):
    assert names(vm, "**.Q") == ["Main.t.Q"]
    assert names(vm, "Main.**.b") == ["Main.pair.b", "Main.pairs[1].b", "Main.pairs[2].b"]


def test_exact_paths_are_case_insensitive_and_canonical(vm):
    assert names(vm, "main.COUNTER", "MAIN.T.et") == ["Main.counter", "Main.t.ET"]


def test_pattern_order_then_declaration_order_without_repeats(vm):
    assert names(vm, "Main.flag", "Main.*")[:3] == ["Main.flag", "Main.counter", "Main.arr[0]"]


def test_no_match_is_an_error_with_a_hint(vm):
    with pytest.raises(WatchError, match="did you mean Main"):
        select_signals(vm, ["Mian.*"])
    with pytest.raises(WatchError):
        select_signals(vm, ["Main.nothing"])


def test_question_mark_stays_in_one_name():
    assert compile_pattern("a.?").fullmatch("a.b")
    assert not compile_pattern("a?b").fullmatch("a.b")


def test_sampler_reads_current_values(vm):
    signals = select_signals(vm, ["Main.counter", "Main.arr[2]", "Main.pair.a"])
    sample = make_sampler(signals)
    assert sample() == (0, 0, 0)
    vm.run(cycles=2)
    assert sample() == (2, 2, 4)
