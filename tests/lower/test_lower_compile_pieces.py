"""The generated module compiled in pieces (`stvm.lower.product.compile_module`): the same
behaviour as one piece, faults and line numbers at the same ST lines, any size of program."""

from __future__ import annotations

import pytest

import stvm.lower.product as product
from core_helpers import cli, run_st, write_st
from stvm.lower.product import compile_module

MANY_FBS = "\n".join(
    f"FUNCTION_BLOCK FB{i} VAR_INPUT x : INT; END_VAR VAR_OUTPUT y : INT; END_VAR y := x + {i}; END_FUNCTION_BLOCK"
    for i in range(60)) + """
PROGRAM Main
VAR """ + " ".join(f"f{i} : FB{i};" for i in range(60)) + """ total : DINT; zero : DINT; q : DINT; END_VAR
""" + "\n".join(f"f{i}(x := {i}); total := total + f{i}.y;" for i in range(60)) + """
q := total / zero;
END_PROGRAM
"""


def test_a_small_module_is_one_piece():
    assert len(compile_module("x = 1\nclass A:\n    pass\n", "<t>")) == 1


def test_pieces_are_cut_before_top_level_classes_and_keep_their_line_numbers(monkeypatch):
    monkeypatch.setattr(product, "CHUNK_LINES", 3)
    source = "class A:\n    a = 1\n    b = 2\n    c = 3\nclass B:\n    x = A.a\ndef f():\n    return 1 / 0\n"
    pieces = compile_module(source, "<t>")
    assert len(pieces) == 2
    ns: dict = {}
    for piece in pieces:
        exec(piece, ns)
    assert ns["B"].x == 1
    with pytest.raises(ZeroDivisionError) as info:
        ns["f"]()
    assert info.traceback[-1].lineno + 1 == 8          # the line of `return 1 / 0` in the module


def test_a_program_compiled_in_many_pieces_runs_and_faults_at_its_st_line(monkeypatch, tmp_path):
    monkeypatch.setattr(product, "CHUNK_LINES", 20)
    values = run_st(MANY_FBS.replace("q := total / zero;", ""), prints=["Main.total"])
    assert values == {"Main.total": sum(2 * i for i in range(60))}
    path = write_st(MANY_FBS, folder=tmp_path)
    rc, _, err = cli(["run", path, "--cycles", "1", "--no-cache"])
    lines = MANY_FBS.splitlines()
    fault_line = next(i for i, line in enumerate(lines, 1) if line.startswith("q := total / zero"))
    assert rc == 3 and f"{path}:{fault_line}:1: fault: integer division by zero" in err, err


def _functions(code, out):
    for const in code.co_consts:
        if hasattr(const, "co_positions"):
            out.append((const.co_name, const.co_firstlineno, list(const.co_positions())))
            _functions(const, out)
    return out


def test_pieces_have_the_line_tables_of_the_whole_module(monkeypatch):
    # every class and function body (what faults, breakpoints and traces read) at the lines and
    # columns compiling the module at once gives them
    monkeypatch.setattr(product, "CHUNK_LINES", 4)
    source = "".join(f"class C{i}:\n    def f(self):\n        x = {i}\n        return (x +\n            1)\n"
                     for i in range(6))
    pieces = compile_module(source, "<t>")
    assert len(pieces) > 2
    moved: list = []
    for piece in pieces:
        _functions(piece, moved)
    assert len(moved) == 12 and moved == _functions(compile(source, "<t>", "exec"), [])


def test_a_syntax_error_in_a_later_piece_is_at_its_module_line(monkeypatch):
    monkeypatch.setattr(product, "CHUNK_LINES", 2)
    source = "class A:\n    a = 1\nclass B:\n    b = (\n"
    with pytest.raises(SyntaxError) as info:
        compile_module(source, "<t>")
    assert info.value.lineno == 4
