"""stvm.syntax: grammar, tree shapes, precedence, comments, case-insensitivity, spans, syntax errors."""

from __future__ import annotations

import pytest
from lark import Lark

from stvm.syntax import nodes as n
from stvm.syntax import parse_expression, parse_text
from stvm.syntax.parser import grammar_text


def expr(text: str) -> n.Expr:
    node, diags = parse_expression(text)
    assert node is not None and not diags, diags
    return node


def unit(text: str, file: str = "t.st") -> n.CompilationUnit:
    u, diags = parse_text(text, file)
    assert not [d for d in diags if d.is_error], diags
    return u


def body(stmts: str) -> tuple[n.Statement, ...]:
    u = unit(f"PROGRAM P\nVAR x, i : INT; b : BOOL; END_VAR\n{stmts}\nEND_PROGRAM\n")
    return u.pous[0].body


def shape(e: n.Expr) -> str:
    """Fully parenthesised rendering of an expression tree (binary/unary ops and leaves)."""
    if isinstance(e, n.Binary):
        return f"({shape(e.left)} {e.op} {shape(e.right)})"
    if isinstance(e, n.Unary):
        return f"({e.op} {shape(e.operand)})"
    if isinstance(e, n.Name):
        return e.text
    if isinstance(e, (n.IntLiteral, n.BoolLiteral)):
        return str(e.value)
    return type(e).__name__


# ---------------------------------------------------------------- the grammar itself
def test_grammar_builds_with_strict_lalr():
    """style.md: a strict build makes terminal collisions and conflicts fail CI."""
    Lark(grammar_text(), parser="lalr", lexer="contextual", strict=True,
         start=["start", "expression"], propagate_positions=True, maybe_placeholders=True)


# ---------------------------------------------------------------- precedence (IEC table, ed. 3)
@pytest.mark.parametrize(("text", "tree"), [
    ("a + b * c", "(a PLUS (b STAR c))"),
    ("a * b + c", "((a STAR b) PLUS c)"),
    ("a - b - c", "((a MINUS b) MINUS c)"),
    ("a / b * c", "((a SLASH b) STAR c)"),
    ("a MOD b + c", "((a MOD b) PLUS c)"),
    ("a ** b * c", "((a POW b) STAR c)"),
    ("-a ** b", "((MINUS a) POW b)"),                 # ed. 3: unary binds tighter than **
    ("NOT a AND b", "((NOT a) AND b)"),
    ("a OR b XOR c AND d", "(a OR (b XOR (c AND d)))"),
    ("a OR b AND c", "(a OR (b AND c))"),
    ("a & b OR c", "((a AMP b) OR c)"),
    ("a = b AND c", "((a EQ b) AND c)"),
    ("a < b = c", "((a LT b) EQ c)"),
    ("a + b < c * d", "((a PLUS b) LT (c STAR d))"),
    ("a <> b OR c >= d", "((a NE b) OR (c GE d))"),
    ("(a + b) * c", "((a PLUS b) STAR c)"),
    ("a + -b", "(a PLUS (MINUS b))"),
    ("NOT NOT a", "(NOT (NOT a))"),
    ("a XOR b XOR c", "((a XOR b) XOR c)"),
    ("a <= b", "(a LE b)"),
    ("a > b", "(a GT b)"),
])
def test_operator_precedence(text, tree):
    assert shape(expr(text)) == tree


@pytest.mark.parametrize("text", ["a and b", "a AND b", "a And b", "a aNd b"])
def test_operator_keywords_case_insensitive(text):
    assert shape(expr(text)) == "(a AND b)"


# ---------------------------------------------------------------- statements
def test_every_statement_kind_parses():
    stmts = body("""
        x := 1;
        IF b THEN x := 1; ELSIF NOT b THEN x := 2; ELSE x := 3; END_IF;
        CASE x OF 1, 2: x := 0; 3..5: x := 1; ELSE x := 2; END_CASE;
        FOR i := 10 TO 1 BY -1 DO CONTINUE; END_FOR;
        WHILE b DO EXIT; END_WHILE;
        REPEAT x := x + 1; UNTIL x > 3 END_REPEAT;
        RETURN;
        ;
        foo();
    """)
    # empty statements (`;`, also the optional `;` after END_IF) parse and may be dropped
    kinds = [type(s).__name__ for s in stmts if not isinstance(s, n.Empty)]
    assert kinds == ["Assign", "If", "Case", "For", "While", "Repeat", "Return", "CallStatement"]
    if_ = stmts[1]
    assert len(if_.branches) == 2 and if_.else_body is not None
    case = stmts[2]
    labels = [[(shape(l.low), l.high and shape(l.high)) for l in labels] for labels, _ in case.elements]
    assert labels == [[("1", None), ("2", None)], [("3", "5")]]
    assert case.else_body is not None
    for_ = stmts[3]
    assert for_.variable.text == "i" and shape(for_.step) == "(MINUS 1)"
    assert isinstance(for_.body[0], n.Continue)
    assert isinstance(stmts[4].body[0], n.Exit)


def test_keywords_and_identifiers_are_case_insensitive():
    u = unit("""
        program Main
        var X : int; flag : Bool; end_var
        if flag then x := 1; elsif TRUE then X := 2; else x := 3; end_if;
        for x := 1 to 2 by 1 do ; end_for;
        while false do exit; end_while;
        repeat x := x; until true end_repeat;
        case x of 1: x := 2; else x := 1; end_case;
        End_Program
    """)
    assert u.pous[0].name == "Main"
    assert len(u.pous[0].body) == 5


def test_case_labels_with_enum_names_and_typed_values():
    stmts = body("CASE x OF Red: x := 1; Green, Color#Blue: x := 2; -5..-1: x := 3; END_CASE;")
    labels = [labels for labels, _ in stmts[0].elements]
    assert isinstance(labels[0][0].low, n.Name) and labels[0][0].low.text == "Red"
    assert isinstance(labels[1][1].low, n.HashLiteral) and labels[1][1].low.text == "Blue"
    assert labels[2][0].high is not None


def test_case_label_name_is_not_confused_with_assignment():
    """`Idle:` starts a new label, `Idle := …` is a statement of the previous label."""
    stmts = body("CASE x OF 1: Idle := 1; Busy: x := 2; END_CASE;")
    (first, first_body), (second, _) = stmts[0].elements
    assert isinstance(first_body[0], n.Assign)
    assert second[0].low.text == "Busy"


# ---------------------------------------------------------------- comments
def test_comment_styles_are_ignored_everywhere():
    u = unit("""
        (* a block comment
           over lines *)
        PROGRAM P // line comment
        VAR x : INT; (* inside a var block *) y : INT; END_VAR
        /* C style */
        x := F(1, (* inside an argument list *) 2 // and here
               );
        y := x (* before the semicolon *);
        END_PROGRAM
    """)
    assert [type(s).__name__ for s in u.pous[0].body] == ["Assign", "Assign"]
    call = u.pous[0].body[0].value
    assert len(call.args) == 2


def test_comment_markers_inside_strings_are_text():
    stmts = body("x := 1; s := '(* not a comment *) // nor this';")
    assert stmts[1].value.value == b"(* not a comment *) // nor this"


# ---------------------------------------------------------------- calls, access paths
def test_call_arguments_formal_output_positional():
    e = expr("f(a := 1, q => z, NOT r => w, 5)")
    assert [(a.kind, a.name) for a in e.args] == [
        ("input", "a"), ("output", "q"), ("output_not", "r"), ("positional", None)]


def test_access_paths():
    e = expr("a.b[1, i + 1].c")
    assert isinstance(e, n.Member) and e.name == "c"
    idx = e.base
    assert isinstance(idx, n.Index) and len(idx.indices) == 2
    assert isinstance(idx.base, n.Member) and idx.base.name == "b"


def test_namespaced_names_and_enum_literals():
    e = expr(r"CBT_Commands_Lib\stCBT_Connection")
    assert isinstance(e, n.Name) and e.parts == ("CBT_Commands_Lib", "stCBT_Connection")
    h = expr(r"\\CBT_Commands_Lib\eCBT_MovCmd_Movement#Line")
    assert isinstance(h, n.HashLiteral)
    assert h.rooted and h.prefix == ("CBT_Commands_Lib", "eCBT_MovCmd_Movement") and h.text == "Line"
    o = expr("_eBYTE_ORDER#_LOW_HIGH")
    assert o.prefix == ("_eBYTE_ORDER",) and o.text == "_LOW_HIGH"


def test_namespace_declaration_qualifies_its_contents():
    u = unit("""
        NAMESPACE Outer.Inner
        TYPE E : (A, B); END_TYPE
        FUNCTION F : INT F := 1; END_FUNCTION
        END_NAMESPACE
    """)
    assert u.types[0].namespace == ("Outer", "Inner")
    assert u.pous[0].namespace == ("Outer", "Inner")


# ---------------------------------------------------------------- declarations
def test_declarations_of_every_section_and_qualifier():
    u = unit("""
        FUNCTION_BLOCK FB
        VAR_INPUT a : INT := 1; END_VAR
        VAR_OUTPUT q : BOOL; END_VAR
        VAR_IN_OUT io : INT; END_VAR
        VAR_TEMP t : INT; END_VAR
        VAR_EXTERNAL g : INT; END_VAR
        VAR CONSTANT K : INT := 3; END_VAR
        VAR RETAIN r : INT; END_VAR
        VAR s1, s2 : STRING[20]; s3 : STRING(7); arr : ARRAY[-1..1, 0..2] OF INT := [9(0)]; END_VAR
        END_FUNCTION_BLOCK
    """)
    blocks = u.pous[0].var_blocks
    assert [b.kind for b in blocks] == ["VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL",
                                        "VAR", "VAR", "VAR"]
    assert blocks[5].constant and "RETAIN" in blocks[6].qualifiers
    decls = blocks[7].decls
    assert [name for name, _ in decls[0].names] == ["s1", "s2"]
    assert isinstance(decls[0].type_spec, n.StringTypeSpec)
    assert isinstance(decls[1].type_spec, n.StringTypeSpec)
    arr = decls[2].type_spec
    assert isinstance(arr, n.ArrayTypeSpec) and len(arr.ranges) == 2
    (count, value), = decls[2].init.items
    assert count == 9 and value.expr == n.IntLiteral(0)


def test_type_declarations():
    u = unit("""
        TYPE
          Color : (Red, Green, Blue);
          Level : INT (Low := 10, High := 20);
          Mode : (Off := 5, On := 7) := On;
          Pt : STRUCT x : INT := 1; y : INT; END_STRUCT;
          MyInt : INT := 7;
          Small : INT (0..10);
          Vec : ARRAY[1..3] OF Pt;
        END_TYPE
    """)
    bodies = {t.name: t.body for t in u.types}
    assert [m[0] for m in bodies["Color"].members] == ["Red", "Green", "Blue"]
    assert bodies["Level"].base.upper() == "INT" and [m[1] for m in bodies["Level"].members] == [10, 20]
    assert bodies["Mode"].default == "On"
    assert isinstance(bodies["Pt"], n.StructDecl) and len(bodies["Pt"].fields) == 2
    assert isinstance(bodies["MyInt"], n.AliasDecl) and bodies["MyInt"].init is not None
    assert isinstance(bodies["Small"].type_spec, n.SubrangeTypeSpec)
    assert (bodies["Small"].type_spec.low, bodies["Small"].type_spec.high) == (0, 10)


def test_configuration_resource_tasks():
    u = unit("""
        CONFIGURATION Cfg
          VAR_GLOBAL g : INT; END_VAR
          RESOURCE Res ON PLC
            TASK Fast (INTERVAL := T#10ms, PRIORITY := 1);
            TASK Slow (INTERVAL := T#50ms, PRIORITY := 4);
            PROGRAM A WITH Fast : ProgA;
            PROGRAM B WITH Slow : ProgB;
          END_RESOURCE
        END_CONFIGURATION
    """)
    cfg = u.configurations[0]
    res = cfg.resources[0]
    assert [t.name for t in res.tasks] == ["Fast", "Slow"]
    assert [(p.instance, p.task, p.type_name) for p in res.programs] == [
        ("A", "Fast", ("ProgA",)), ("B", "Slow", ("ProgB",))]


# ---------------------------------------------------------------- spans
def test_spans_point_at_the_source_and_stay_out_of_equality():
    text_a = "PROGRAM P\nVAR x : INT; END_VAR\nx := 1 + 2;\nEND_PROGRAM\n"
    text_b = "PROGRAM P VAR x : INT; END_VAR\n\n\n   x   :=   1+2 ;   END_PROGRAM"
    a = unit(text_a).pous[0].body[0]
    b = unit(text_b).pous[0].body[0]
    assert a == b                       # reformatting does not change the tree
    assert (a.span.line, a.span.column) == (3, 1)
    assert (b.span.line, b.span.column) == (4, 4)
    assert (a.value.span.line, a.value.span.column) == (3, 6)
    assert a.span.file == "t.st"


# ---------------------------------------------------------------- syntax errors
@pytest.mark.parametrize(("text", "line", "col", "words"), [
    ("PROGRAM P\nVAR x : INT; END_VAR\nx := 1 +;\nEND_PROGRAM\n", 3, 9, "unexpected ';'"),
    ("PROGRAM P\nVAR x : INT; END_VAR\nx := 1\nEND_PROGRAM\n", 4, 1, "unexpected 'END_PROGRAM'"),
    ("PROGRAM P\nVAR x : INT; END_VAR\nIF x THEN\n", 3, None, "unexpected end of file"),
    ("PROGRAM P\nVAR s : STRING; END_VAR\ns := 'abc;\nEND_PROGRAM\n", 3, 6, "string"),
    ("PROGRAM P\nVAR x : INT; END_VAR\nx := 1 ? 2;\nEND_PROGRAM\n", 3, 8, "unexpected character"),
    ("PROGRAM P\nVAR x : INT END_VAR\nEND_PROGRAM\n", 2, 13, "unexpected 'END_VAR'"),
])
def test_syntax_errors_are_diagnostics_with_positions(text, line, col, words):
    u, diags = parse_text(text, "bad.st")
    assert len(diags) == 1
    d = diags[0]
    assert d.is_error and words in d.message
    assert d.span.file == "bad.st" and d.span.line == line
    if col is not None:
        assert d.span.column == col
    assert u.pous == ()


def test_parse_expression_rejects_garbage_without_exception():
    node, diags = parse_expression("1 +* 2")
    assert node is None and diags and diags[0].is_error
