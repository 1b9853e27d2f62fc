"""A load leaves no cyclic garbage behind that holds the syntax tree or the checker (issue 17,
large inputs): with the collector paused during a load and the survivors moved to the oldest
generation unscanned (`stvm.heap.collector_paused(age_survivors=True)`), such garbage would stay
until a full collection."""

from __future__ import annotations

import gc

from core_helpers import write_st

import stvm
from stvm.semantics.checker import Checker
from stvm.syntax import nodes as n

SOURCE = """
TYPE Inner : STRUCT a : INT; END_STRUCT; END_TYPE
TYPE Outer : STRUCT i : Inner; END_STRUCT; END_TYPE
FUNCTION_BLOCK Base
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
y := x * 2 + 1 - (x MOD 3);
END_FUNCTION_BLOCK
FUNCTION_BLOCK Derived EXTENDS Base
VAR o : Outer; END_VAR
o.i.a := y + x * (x - 1);
END_FUNCTION_BLOCK
PROGRAM Main
VAR d : Derived; k : INT; END_VAR
d(x := k); k := k + 1;
END_PROGRAM
"""


def live(cls) -> int:
    return sum(1 for o in gc.get_objects() if isinstance(o, cls))


def test_load_frees_the_checker_and_the_syntax_tree_without_the_collector():
    path = write_st(SOURCE)
    stvm.load([path], use_cache=False)   # the stdlib's units stay (memoised in the process)
    gc.collect()
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        # other tests of this process may hold checkers and trees on purpose: count this load's own
        before, checkers = live(n.Binary), live(Checker)
        project = stvm.load([path], use_cache=False)
        # refcounting alone freed them: nothing cyclic kept the checker or the tree alive
        assert live(Checker) == checkers, ("a Checker outlived its load: a cycle holds it (a nested function "
                                    "that calls itself needs `del name` after its last use)")
        assert live(n.Binary) == before, "syntax nodes outlived their load: a cycle holds them"
        project.start(scan="10ms").run(cycles=2)
    finally:
        if was_enabled:
            gc.enable()
