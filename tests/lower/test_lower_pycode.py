"""The line writer's map from generated lines to ST spans (stvm/lower/pycode.py `CodeWriter`):
what `LineMap.add` keeps, one entry per run of lines with the same span, also across bodies
written apart and appended."""

from __future__ import annotations

from stvm.lower.pycode import CodeWriter
from stvm.source import Span

A, B, C = (Span("main.st", line, 1, line, 9) for line in (3, 4, 5))


def test_lines_map_to_the_span_they_were_written_under_and_glue_to_none():
    w = CodeWriter()
    w.line("# header")              # no span yet: not mapped
    w.span = A
    w.line("x = 1")
    w.line("y = 2")
    w.blank_span()
    w.line("pass")                  # glue after mapped code: mapped to None
    w.line("pass")                  # and the lines after it with it
    assert w.line_map.lines == [2, 3, 4] and w.line_map.spans == [A, A, None]
    assert [w.line_map.span_at(i) for i in range(1, 6)] == [None, A, A, None, None]


def test_an_appended_body_keeps_its_spans_at_its_new_lines():
    outer, body = CodeWriter(), CodeWriter()
    outer.span = A
    outer.line("try:")
    body.indent = 1
    body.span = B
    body.line("a = 1")
    body.span = C
    body.line("b = 2")
    body.line("c = 3")
    outer.append(body)
    outer.span = A
    outer.line("finally:")
    assert outer.lines == ["try:", "    a = 1", "    b = 2", "    c = 3", "finally:"]
    assert [outer.line_map.span_at(i) for i in range(1, 6)] == [A, B, C, C, A]
    assert outer.line_map.lines == [1, 2, 3, 4, 5]


def test_appending_an_empty_body_changes_no_map():
    outer = CodeWriter()
    outer.span = A
    outer.line("x = 1")
    outer.append(CodeWriter())
    assert outer.line_map.lines == [1] and outer.line_map.spans == [A]
