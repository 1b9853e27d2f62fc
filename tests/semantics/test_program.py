"""stvm/semantics/program.py, pass 5 of the checker: the whole-program rules, which read the call
facts the body checks recorded."""

from __future__ import annotations

from checker_passes import declared, messages

from stvm.semantics.body import BodyChecker
from stvm.semantics.program import _cycles_closed, _longest_paths


def bodies_checked(source: str):
    ck = declared(source)
    for key, pou in ck.ctx.index.pou_nodes.items():
        BodyChecker(ck, ck.ctx.pous[key], pou).check()
    return ck


def test_cycles_are_closed_in_graph_order_with_sorted_callees():
    graph = {"a": {"c", "b"}, "b": {"a"}, "c": {"c"}, "d": set()}
    assert _cycles_closed(graph) == [["a", "b", "a"], ["c", "c"]]


def test_longest_paths_count_nodes_and_ignore_edges_closing_a_cycle():
    graph = {"p": [("x", "q")], "q": [("y", "r")], "r": [("z", "p")]}
    depth, first = _longest_paths(graph)
    assert depth == {"r": 1, "q": 2, "p": 3} and first["p"] == ("x", "q") and first["r"] is None


def test_recursion_is_found_from_the_calls_the_bodies_recorded():
    ck = bodies_checked("FUNCTION F : INT\nVAR_INPUT n : INT; END_VAR\nF := G(n);\nEND_FUNCTION\n"
                        "FUNCTION G : INT\nVAR_INPUT n : INT; END_VAR\nG := F(n);\nEND_FUNCTION\n")
    assert messages(ck) == []
    ck.program.check_recursion()
    assert messages(ck) == [("E027", "recursive call F -> G -> F: IEC 61131-3 does not allow recursion")]


def test_a_function_block_containing_itself_is_reported_and_programs_are_listed():
    ck = bodies_checked("FUNCTION_BLOCK Loop\nVAR inner : Loop; END_VAR\nEND_FUNCTION_BLOCK\n"
                        "PROGRAM Main\nEND_PROGRAM\n")
    assert ck.program.check_nesting_depth() is True
    ck.program.check_containment()
    assert [d.code for d in ck.ctx.diags] == ["E026"]
    assert "Loop" in ck.ctx.diags[0].message
    assert ck.program.check_configuration() == ([], ["Main"])
