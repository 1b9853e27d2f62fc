"""Syntax-error recovery (stvm/syntax/parser.py): every missing ';' is reported in one run; any
other syntax error stops at the first, so no invented follow-up errors appear."""

from stvm.syntax import parse_text

MISSING_SEMICOLONS = """PROGRAM Main
VAR x : INT; y : INT END_VAR
x := 1
y := 2
x := 3;
IF x > 0 THEN y := 1 END_IF;
END_PROGRAM
"""


def test_each_missing_semicolon_is_reported():
    unit, diags = parse_text(MISSING_SEMICOLONS, "m.st")
    assert [(d.span.line, d.span.column) for d in diags] == [(2, 22), (4, 1), (5, 1), (6, 22)]
    assert all(d.is_error and "expected ';'" in d.message for d in diags)
    assert unit.pous == ()   # a file with syntax errors is never run


def test_recovery_does_not_invent_errors_after_a_real_one():
    text = "PROGRAM Main\nVAR x : INT; END_VAR\nx := 1 + ;\nx := 2;\nx := (3;\nEND_PROGRAM\n"
    unit, diags = parse_text(text, "m.st")
    assert len(diags) == 1
    assert (diags[0].span.line, diags[0].span.column) == (3, 10)


def test_missing_semicolon_then_a_real_error_reports_both_in_order():
    text = "PROGRAM Main\nVAR x : INT; END_VAR\nx := 1\nx := * 2;\nEND_PROGRAM\n"
    unit, diags = parse_text(text, "m.st")
    assert [(d.span.line, d.span.column) for d in diags] == [(4, 1), (4, 6)]
