"""stvm.lower: ST → Python source once per POU, a line map back to ST, no AST walking at run time."""

from __future__ import annotations

import ast
import re

import pytest

from core_helpers import load_st, start_st

SOURCE = """PROGRAM Main
VAR x : INT; arr : ARRAY[1..3] OF INT; i : INT; f : Inner; s : STRING; END_VAR
x := x + 1;
IF x > 2 THEN
  x := 0;
END_IF;
FOR i := 1 TO 3 DO
  arr[i] := i;
END_FOR;
f(a := x);
s := 'literal text';
END_PROGRAM
FUNCTION_BLOCK Inner
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
q := a * 2;
END_FUNCTION_BLOCK
"""

STATEMENT_LINES = [3, 4, 5, 7, 8, 10, 11, 16]


@pytest.fixture(scope="module")
def project():
    return load_st(SOURCE)


def user_file(project) -> str:
    return next(name for name in project.sources if not name.startswith("<"))


def test_generated_source_is_valid_python(project):
    ast.parse(project.lowered.source)
    compile(project.lowered.source, "<check>", "exec")


def test_every_st_statement_has_generated_lines(project):
    file = user_file(project)
    line_map = project.lowered.line_map
    for st_line in STATEMENT_LINES:
        gen_lines = line_map.lines_for(file, st_line)
        assert gen_lines, f"ST line {st_line} has no generated code"
        for g in gen_lines:
            span = line_map.span_at(g)
            assert span.file == file and span.line == st_line


def test_line_map_never_points_at_lines_without_statements(project):
    file = user_file(project)
    mapped = {span.line for span in project.lowered.line_map.spans if span is not None and span.file == file}
    assert mapped <= set(STATEMENT_LINES) | {1, 13}     # statements (and at most the POU headers)


def test_st_names_are_mangled(project):
    tree = ast.parse(project.lowered.source)
    attrs = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)}
    assert "v_x" in attrs and "v_arr" in attrs
    assert "x" not in attrs and "arr" not in attrs


def test_string_literals_enter_through_repr(project):
    tree = ast.parse(project.lowered.source)
    consts = [node.value for node in ast.walk(tree) if isinstance(node, ast.Constant)]
    assert b"literal text" in consts


def test_runtime_does_not_walk_the_tree(project, monkeypatch):
    """After lowering, scans run compiled code: breaking the tree classes changes nothing."""
    from stvm.syntax import nodes as n
    vm = project.start()
    for cls in (n.Assign, n.If, n.For, n.Binary, n.Name):
        monkeypatch.setattr(cls, "__getattribute__", lambda *a: (_ for _ in ()).throw(AssertionError("AST walked")))
    vm.run(cycles=3)
    monkeypatch.undo()
    assert vm["Main.x"] == 0 and vm["Main.arr"] == [1, 2, 3] and vm["Main.f.q"] == 0


def test_generated_module_has_one_class_per_fb_and_program(project):
    classes = project.lowered.classes
    assert "main" in classes and "inner" in classes
    assert re.search(rf"^class {classes['main']}\b", project.lowered.source, re.M)
    assert re.search(rf"^class {classes['inner']}\b", project.lowered.source, re.M)


def test_glue_lines_do_not_borrow_the_previous_units_statement(project):
    """Lines between POUs (class headers, prologues) map to no statement rather than the last one
    of the unit before (that once blamed <stdlib> statements for faults in user functions)."""
    source_lines = project.lowered.source.splitlines()
    line_map = project.lowered.line_map
    for number, text in enumerate(source_lines, start=1):
        if text.startswith(("class ", "def ")):
            assert line_map.span_at(number) is None, (number, text)


def test_fault_location_uses_the_line_map():
    vm = start_st("PROGRAM Main\nVAR z : INT; a : INT; END_VAR\n\n\n   a := 1 / z;\nEND_PROGRAM\n")
    import stvm
    with pytest.raises(stvm.RuntimeFault) as info:
        vm.scan()
    assert (info.value.span.line, info.value.span.column) == (5, 4)
