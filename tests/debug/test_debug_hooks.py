"""Breakpoints compiled into the generated code (stvm/debug/hooks.py): the worker runs untraced
until something needs line events, and a stop is the same whether the hook or the trace function
finds it."""

from __future__ import annotations

import sys

from core_helpers import write_st
from debug_helpers import small_build, small_line, small_path, start_engine

from stvm.debug.build import load_debug
from stvm.debug.engine import BREAKPOINT, CONTINUE, STEP, STEPPED
from stvm.debug.hooks import HOOK_NAME

T = 30


def _counter_call(engine):
    cls = engine.vm.namespace[engine.build.project.lowered.classes["counter"]]
    return vars(cls)["__call__"]


def _record_trace(engine) -> list:
    """The worker's trace function at every stop (listeners run in the worker thread)."""
    seen: list = []
    engine.listeners.append(lambda event: seen.append(sys.gettrace()) if event is not None else None)
    return seen


def test_a_breakpoint_is_a_call_compiled_in_and_continue_runs_untraced():
    engine = start_engine(small_build())
    try:
        built = _counter_call(engine).__code__
        traces = _record_trace(engine)
        engine.add_breakpoint(str(small_path()), small_line("Count := Count + 1;"))
        hooked = _counter_call(engine).__code__
        assert hooked is not built and HOOK_NAME in hooked.co_names and HOOK_NAME not in built.co_names
        assert hooked.co_qualname == built.co_qualname and hooked.co_firstlineno == built.co_firstlineno
        event = engine.run(CONTINUE, timeout=T)
        assert event.reason == BREAKPOINT and event.span.line == small_line("Count := Count + 1;")
        assert traces == [None]             # found by the compiled-in call: no trace function ran
        engine.delete_breakpoint()
        assert _counter_call(engine).__code__ is built   # the build's own code again
    finally:
        engine.terminate()


def test_a_hooked_line_reached_by_stepping_stops_once():
    engine = start_engine(small_build())
    try:
        engine.add_breakpoint(str(small_path()), small_line("Count := Count + 1;"))
        engine.add_breakpoint(str(small_path()), small_line("history[Count MOD 5]"))
        assert engine.run(CONTINUE, timeout=T).span.line == small_line("Count := Count + 1;")
        event = engine.run(STEP, timeout=T)     # the trace function sees the next hooked line first
        assert event.reason == BREAKPOINT and event.span.line == small_line("history[Count MOD 5]")
        event = engine.run(STEP, timeout=T)     # the hook call that follows does not stop again
        assert event.reason == STEPPED and event.span.line == small_line("tmp := x * 2;")
        assert [bp.hits for bp in engine.breakpoints.values()] == [1, 1]
    finally:
        engine.terminate()


def test_a_breakpoint_on_a_while_test_stops_at_every_iteration():
    text = ("PROGRAM Loop\nVAR\n    k : INT;\n    n : INT;\nEND_VAR\nk := 0;\nWHILE k < 3 DO\n    k := k + 1;\n"
            "END_WHILE;\nn := n + 1;\nEND_PROGRAM\n")
    engine = start_engine(load_debug([str(write_st(text, "while_hook.st"))]))
    try:
        engine.add_breakpoint("while_hook.st", 7)
        seen = []
        for _ in range(5):
            event = engine.run(CONTINUE, timeout=T)
            assert event.reason == BREAKPOINT and event.span.line == 7
            seen.append((event.scan, engine.evaluate_text("k")))
        assert seen == [(0, "0"), (0, "1"), (0, "2"), (0, "3"), (1, "0")]
    finally:
        engine.terminate()


def test_stepping_traces_and_continue_drops_the_trace_function_again():
    engine = start_engine(small_build())
    try:
        traces = _record_trace(engine)
        engine.add_breakpoint(str(small_path()), small_line("Count := Count + 1;"))
        engine.run(CONTINUE, timeout=T)
        engine.run(STEP, timeout=T)             # a stop found by the trace function
        engine.run(CONTINUE, timeout=T)         # back to the compiled-in call, untraced
        assert traces[0] is None and traces[1] is not None and traces[2] is None
    finally:
        engine.terminate()


def test_a_breakpoint_set_while_stopped_hits_later_in_the_same_call():
    engine = start_engine(small_build())
    try:
        engine.add_breakpoint(str(small_path()), small_line("c(Enable := run);"))
        event = engine.run(CONTINUE, timeout=T)
        assert event.scan == 0
        # the running call of Main has the code built before this breakpoint: traced till it ends
        engine.add_breakpoint(str(small_path()), small_line("grid[2, 3] := i;"))
        event = engine.run(CONTINUE, timeout=T)
        assert event.reason == BREAKPOINT and event.scan == 0
        assert event.span.line == small_line("grid[2, 3] := i;")
        event = engine.run(CONTINUE, timeout=T)     # the next scan: the first breakpoint, untraced
        assert event.scan == 1 and event.span.line == small_line("c(Enable := run);")
    finally:
        engine.terminate()
