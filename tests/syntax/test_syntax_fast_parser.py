"""The fast LALR driver (stvm/syntax/lalr.py) gives exactly what Lark's own parser and tree give.

`parse_text` runs the driver and falls back to Lark on any error; `parse_text_lark` is Lark's
path alone (the reference). Both are compared field by field, spans included (they are out of
`==` on purpose), over every .st file in the repository, hypothesis-generated programs (valid
ones, and mutated ones that mostly are not), expressions, deep nesting, and a small synthetic
grammar that uses the Lark features stvm's grammar does not (so a grammar change cannot meet
an untested corner of the driver).
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import lark
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lark import Lark, Token, Tree

from stvm.syntax import lalr
from stvm.syntax import parser as P

ROOT = Path(__file__).resolve().parents[2]
ST_FILES = sorted(p for p in ROOT.rglob("*.st") if ".git" not in p.parts and "node_modules" not in p.parts)


def dump(x):
    """Everything in a parse result, spans and token positions included."""
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return (type(x).__name__,) + tuple((f.name, dump(getattr(x, f.name))) for f in dataclasses.fields(x))
    if isinstance(x, Token):
        return ("Token", x.type, str(x), x.line, x.column, x.end_line, x.end_column, x.start_pos, x.end_pos)
    if isinstance(x, Tree):
        return ("Tree", x.data, dump(x.children))
    if isinstance(x, (list, tuple)):
        return (type(x).__name__,) + tuple(dump(y) for y in x)
    if isinstance(x, dict):
        return tuple(sorted((k, dump(v)) for k, v in x.items()))
    return (type(x).__name__, x)


def fast_only(text: str, start: str = "start"):
    """The driver alone: its result, or the Fallback it raised."""
    driver = P._driver(start)
    assert driver is not None, "the fast driver is disabled (Lark internals changed?)"
    return driver.parse(text, P._ToNodes("t.st", P.DEFAULT_SETTINGS, []))


def assert_same(text: str, file: str = "t.st") -> tuple:
    fast = P.parse_text(text, file)
    ref = P.parse_text_lark(text, file)
    assert dump(fast) == dump(ref)
    return ref


# ---------------------------------------------------------------- Lark's internals are what we use
def test_lark_internals_are_the_ones_the_driver_knows():
    problems = lalr.check_lark_internals(P._parser(), P._ToNodes)
    assert problems == [], (f"lark {lark.__version__}: the fast driver cannot use this Lark version "
                            f"({problems}); adjust stvm/syntax/lalr.py or the lark pin in pyproject.toml")
    assert P._driver("start") is not None and P._driver("expression") is not None


def test_the_lark_pin_covers_the_installed_version():
    text = (ROOT / "pyproject.toml").read_text()
    pin = re.search(r'"lark>=([0-9.]+),<([0-9.]+)"', text)
    assert pin, "pyproject.toml must pin lark with an upper bound (the driver uses its internals)"
    version = tuple(int(p) for p in lark.__version__.split(".")[:2])
    low = tuple(int(p) for p in pin.group(1).split(".")[:2])
    high = tuple(int(p) for p in pin.group(2).split(".")[:2])
    assert low <= version < high


# ---------------------------------------------------------------- every ST file in the repository
@pytest.mark.parametrize("path", ST_FILES, ids=[str(p.relative_to(ROOT)) for p in ST_FILES])
def test_every_st_file_parses_the_same(path):
    text = path.read_text(encoding="utf-8", errors="replace")
    unit, diags = assert_same(text, str(path))
    if not any(d.code == "E001" or d.code == "E002" for d in diags):
        fast_only(text)          # valid sources take the fast path (no Fallback raised)


def test_the_stdlib_parses_the_same():
    from stvm.project import _stdlib
    from stvm.settings import DEFAULT_SETTINGS
    for name, text in _stdlib(DEFAULT_SETTINGS):
        assert_same(text, name)
        fast_only(text)


def test_the_nesting_and_recursion_checks_see_calls_in_codegen_order():
    # the fast `calls_in` (no per-node reflection) against the plain walk the lowering follows
    from stvm.syntax import nodes as n
    from stvm.syntax.walk import calls_in, walk
    seen = 0
    for path in ST_FILES:
        unit, _ = P.parse_text(path.read_text(encoding="utf-8", errors="replace"), str(path))
        for pou in unit.pous:
            expected = [node for node in walk(pou.body) if isinstance(node, n.Call)]
            assert [id(c) for c in calls_in(pou.body)] == [id(c) for c in expected]
            seen += len(expected)
    assert seen > 500


# ---------------------------------------------------------------- generated programs
def kw(word: str):
    """A keyword in random letter case (keywords are case-insensitive)."""
    return st.lists(st.booleans(), min_size=len(word), max_size=len(word)).map(
        lambda ups: "".join(c.upper() if u else c.lower() for c, u in zip(word, ups)))


GAP = st.sampled_from([" ", "  ", "\n", "\t", " (* c *) ", "\n// line\n", " /* b\n */ ", "\r\n"])
NAMES = st.sampled_from(["a", "b", "x1", "Foo", "_t", "arr", "fb", "s", "r", "en", "Value_2", "on", "with", "at"])
INTS = st.sampled_from(["0", "1", "42", "1_000", "16#FF", "2#1010", "8#17", "16#dead_BEEF"])
LITERALS = st.one_of(
    INTS,
    st.sampled_from(["1.5", "2.0e3", "1e-3", "3_1.0", "TRUE", "false", "T#5ms", "TIME#1h2m3s", "t#-1.5s",
                     "LTIME#1d", "D#2024-02-29", "DATE#2023-13-01", "TOD#12:30:15.5", "TIME_OF_DAY#1:2",
                     "DT#2024-01-02-03:04:05", "INT#5", "REAL#-1.5e3", "BYTE#16#0A", "BOOL#TRUE", "Color#Red",
                     "_eBYTE_ORDER#_LOW_HIGH", "\\\\Lib\\eType#Value", "'text'", "'it$'s $N$$'", "'$41'",
                     "''", "\"dq\"", "'$Z'"]))


def access(name_st):
    base = st.one_of(name_st, st.builds(lambda a, b: f"{a}\\{b}", name_st, name_st),
                     st.builds(lambda a: f"\\\\{a}", name_st))
    suffix = st.sampled_from([".m", "[1]", "[i, 2]", ".%X3", ".%b1", ".5", "^", "()", ".q.r", "(1, 2)",
                              "(IN := a, PT => b)", "(NOT q => b)"])
    return st.builds(lambda b, ss: b + "".join(ss), base, st.lists(suffix, max_size=3))


def expressions():
    leaf = st.one_of(LITERALS, access(NAMES))
    ops = st.sampled_from(["+", "-", "*", "/", "MOD", "mod", "**", "AND", "&", "OR", "XOR", "=", "<>", "<", ">",
                           "<=", ">="])

    def extend(inner):
        return st.one_of(
            st.builds(lambda a, o, g, b: f"{a}{g}{o}{g}{b}", inner, ops, GAP, inner),
            st.builds(lambda o, a: f"{o} {a}", st.sampled_from(["NOT", "-", "+", "not"]), inner),
            st.builds(lambda a: f"({a})", inner),
            st.builds(lambda f, args: f"{f}({', '.join(args)})", NAMES, st.lists(inner, max_size=3)),
            st.builds(lambda f, a, b: f"{f}({a}, {b})", st.sampled_from(["MOD", "AND", "OR", "XOR"]), inner, inner),
            st.builds(lambda n_, a: f"{n_}(x := {a})", NAMES, inner),
        )
    return st.recursive(leaf, extend, max_leaves=12)


EXPR = expressions()


def statements():
    simple = st.one_of(
        st.builds(lambda a, e: f"{a} := {e};", access(NAMES), EXPR),
        st.builds(lambda a, e: f"{a} REF= {e};", NAMES, EXPR),
        st.builds(lambda a: f"{a};", access(NAMES)),
        st.sampled_from(["EXIT;", "continue;", "RETURN;", ";"]),
    )

    def extend(inner):
        body = st.lists(inner, max_size=3).map(" ".join)
        label = st.one_of(INTS, st.sampled_from(["-1", "+2", "Idle", "Color#Red", "1..5", "A, B", "0, 2..3"]))
        return st.one_of(
            st.builds(lambda c, b, e, ee: f"IF {c} THEN {b} {e} {ee} END_IF;", EXPR, body,
                      st.lists(st.builds(lambda c, b: f"ELSIF {c} THEN {b}", EXPR, body), max_size=2).map(" ".join),
                      st.one_of(st.just(""), body.map(lambda b: f"ELSE {b}"))),
            st.builds(lambda s, els, e: f"CASE {s} OF {els} {e} END_CASE;", EXPR,
                      st.lists(st.builds(lambda lb, b: f"{lb}: {b}", label, body), max_size=3).map(" ".join),
                      st.one_of(st.just(""), body.map(lambda b: f"ELSE {b}"))),
            st.builds(lambda v, a, b, by, bd: f"FOR {v} := {a} TO {b}{by} DO {bd} END_FOR;", NAMES, EXPR, EXPR,
                      st.one_of(st.just(""), EXPR.map(lambda e: f" BY {e}")), body),
            st.builds(lambda c, b: f"WHILE {c} DO {b} END_WHILE;", EXPR, body),
            st.builds(lambda b, c: f"REPEAT {b} UNTIL {c} END_REPEAT;", body, EXPR),
        )
    return st.recursive(simple, extend, max_leaves=10)


TYPES = st.sampled_from(["INT", "BOOL", "REAL", "STRING[20]", "STRING(5)", "WSTRING", "ARRAY[0..9] OF INT",
                         "ARRAY[1..2, 0..3] OF LREAL", "ARRAY[*] OF INT", "REF_TO INT", "POINTER TO BYTE",
                         "REFERENCE TO DINT", "TON", "Lib\\T", "\\\\Lib\\T", "INT(0..100)", "Color"])
INITS = st.sampled_from(["", " := 5", " := [1, 2, 3(0)]", " := (a := 1, b := TRUE)", " := T#1s", " := [2(1), 4()]",
                         " := 'x'", " := -3"])


def var_blocks():
    decl = st.builds(lambda ns, at, t, i: f"{', '.join(ns)}{at} : {t}{i};",
                     st.lists(NAMES, min_size=1, max_size=2), st.sampled_from(["", " AT %IX0.1", " AT %MW10"]),
                     TYPES, INITS)
    kind = st.sampled_from(["VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL",
                            "VAR_STAT", "var"])
    qual = st.sampled_from(["", " CONSTANT", " RETAIN", " NON_RETAIN", " PERSISTENT"])
    return st.builds(lambda k, q, ds: f"{k}{q}\n{' '.join(ds)}\nEND_VAR", kind, qual, st.lists(decl, max_size=3))


TYPE_BLOCK = st.sampled_from([
    "TYPE S : STRUCT a : INT; b : BOOL := TRUE; END_STRUCT; END_TYPE",
    "TYPE Color : (Red, Green := 5, Blue) := Red; E2 : INT (A := -1, B := 2); END_TYPE",
    "TYPE Alias : ARRAY[0..3] OF REAL := [4(0.0)]; Sub : INT (0..10); R : REF_TO S; END_TYPE",
])
CONFIG = st.sampled_from([
    "CONFIGURATION C VAR_GLOBAL g : INT; END_VAR RESOURCE R ON PLC TASK T(INTERVAL := T#10ms, PRIORITY := 1); "
    "PROGRAM Inst WITH T : Main(x := 1, y => g); END_RESOURCE END_CONFIGURATION",
    "CONFIGURATION C TASK T(INTERVAL := T#1ms); PROGRAM P1 WITH T : Main; END_CONFIGURATION",
])


@st.composite
def programs(draw):
    parts = []
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["PROGRAM", "FUNCTION_BLOCK", "FUNCTION", "function_block"]))
        name = draw(NAMES)
        ret = " : INT" if kind == "FUNCTION" else ""
        pragma = draw(st.sampled_from(["", "{attribute 'hide'} ", "{a}{b} "]))
        blocks = " ".join(draw(st.lists(var_blocks(), max_size=2)))
        body = draw(GAP).join(draw(st.lists(statements(), max_size=4)))
        end = {"PROGRAM": "END_PROGRAM", "FUNCTION": "END_FUNCTION"}.get(kind, "END_FUNCTION_BLOCK")
        parts.append(f"{pragma}{kind} {name}{ret}\n{blocks}\n{body}\n{end}{draw(st.sampled_from(['', ';']))}")
    if draw(st.booleans()):
        parts.insert(0, draw(TYPE_BLOCK))
    if draw(st.booleans()):
        parts.append(draw(CONFIG))
    if draw(st.booleans()):
        parts = ["NAMESPACE Lib.Sub"] + parts + ["END_NAMESPACE"]
    return draw(GAP).join(parts) + draw(st.sampled_from(["", "\n", "\n\n  "]))


FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@FUZZ
@given(programs())
def test_generated_programs_parse_the_same(text):
    unit, diags = assert_same(text)
    if not any(d.code in ("E001", "E002") for d in diags):
        fast_only(text)


@FUZZ
@given(programs(), st.data())
def test_mutated_programs_parse_the_same(text, data):
    """Mostly syntax errors (then the driver hands over to Lark, whose diagnostics stand)."""
    i = data.draw(st.integers(0, max(len(text) - 1, 0)))
    edit = data.draw(st.sampled_from(["delete", "insert", "swap"]))
    char = data.draw(st.sampled_from(list(";:=()[],.'\"#$*\n ") + ["END_IF", "x", "1", "\x00", "é", "(*"]))
    if edit == "delete":
        text = text[:i] + text[i + 1:]
    elif edit == "insert":
        text = text[:i] + char + text[i:]
    else:
        text = text[:i] + char + text[i + 1:]
    assert_same(text)


@FUZZ
@given(EXPR)
def test_generated_expressions_parse_the_same(text):
    fast = P.parse_expression(text)
    ref = P.parse_expression_lark(text)
    assert dump(fast) == dump(ref)
    if ref[0] is not None:
        fast_only(text, "expression")


def test_empty_and_blank_inputs():
    for text in ["", " ", "\n\n", "(* only a comment *)", "// x"]:
        assert_same(text)
    for text in ["", " ", "1 +", "a.", ")"]:
        assert dump(P.parse_expression(text)) == dump(P.parse_expression_lark(text))


# ---------------------------------------------------------------- deep nesting stays Lark's business
@pytest.mark.parametrize("depth", [10, 60, 200, 1200])
def test_deep_nesting_gives_lark_results(depth):
    text = ("PROGRAM P VAR x, y : INT; END_VAR\ny := " + "(" * depth + "x" + " + 1)" * depth + ";\n"
            + "x := x" + ".m" * depth + ";\n" + "IF x THEN " * (depth // 10) + "y := 1;" + " END_IF;" * (depth // 10)
            + "\nEND_PROGRAM\n")
    assert_same(text)     # "nesting too deep" (E003) or not, as Lark's recursion limit decides
    if depth * 2 < lalr.MAX_DEPTH:
        fast_only(text)
    else:
        with pytest.raises(lalr.Fallback):
            fast_only(text)


# ---------------------------------------------------------------- a synthetic grammar: Lark's other features
SYNTHETIC = r"""
start: item*
?item: pair | single | opt | bang | wrapped | quiet | nested | group
pair: NAME "=" value ";"
?value: atom
      | "(" value ")"
      | value "+" atom          -> plus
      | "?" [NUM]               -> maybe
?atom: NAME | NUM | "-" atom -> neg
single: "S" _names ";"
_names: NAME ("," NAME)*
opt: "O" [NAME] [NUM] ";"
!bang: "!" NAME ";"
?wrapped: "W" _one ";"
_one: NAME | NUM | "<" ">"
quiet: "Q" ";"
nested: "N" "{" item* "}"
?group: "G" [value] ";"
NAME: /[a-z][a-z0-9]*/
NUM: /[0-9]+/
%ignore /[ \t\n]+/
%ignore /#[^\n]*/
"""


def _record(name):
    def fn(self, meta, children):
        if meta.__class__ is lalr.Meta2:
            pos = None if meta.empty else (meta.line, meta.column, meta.end_line, meta.end_column)
        else:
            pos = None if getattr(meta, "empty", True) else (meta.line, meta.column, meta.end_line, meta.end_column)
        return (name, pos, list(children))
    return fn


# every rule and alias records (name, position, children), except `opt`: it becomes a lark Tree
Recorder = type("Recorder", (), {name: _record(name) for name in
                                 ["start", "pair", "plus", "maybe", "neg", "single", "bang", "wrapped", "quiet",
                                  "nested", "group"]})


@pytest.fixture(scope="module")
def synthetic():
    parser = Lark(SYNTHETIC, parser="lalr", lexer="contextual", propagate_positions=True, maybe_placeholders=True)
    return parser, lalr.Driver(parser, "start", Recorder)


def synthetic_reference(parser, text):
    return P._FromTree(Recorder()).transform(parser.parse(text))


SYN_VALUE = st.recursive(st.sampled_from(["a", "b1", "7", "- x", "?", "? 3"]),
                         lambda inner: st.one_of(st.builds(lambda v: f"({v})", inner),
                                                 st.builds(lambda v, a: f"{v} + {a}", inner,
                                                           st.sampled_from(["c", "9", "-d"]))),
                         max_leaves=6)
SYN_ITEM = st.recursive(
    st.one_of(st.builds(lambda v: f"p = {v};", SYN_VALUE), st.sampled_from(
        ["S a;", "S a, b, c;", "O;", "O x;", "O 5;", "O x 5;", "! n;", "W w;", "W 4;", "W <>;", "Q;", "G;",
         "# note\n"]),
        st.builds(lambda v: f"G {v};", SYN_VALUE)),
    lambda inner: st.builds(lambda items: "N {" + " ".join(items) + "}", st.lists(inner, max_size=3)),
    max_leaves=8)


@settings(max_examples=200, deadline=None)
@given(st.lists(SYN_ITEM, max_size=6), st.sampled_from([" ", "\n", "  \n\t"]))
def test_synthetic_grammar_matches_lark(synthetic, items, gap):
    parser, driver = synthetic
    text = gap.join(items)
    assert dump(driver.parse(text, Recorder())) == dump(synthetic_reference(parser, text))


def test_synthetic_grammar_corners(synthetic):
    parser, driver = synthetic
    for text in ["", "W <>;", "G;", "G ?;", "N { N { } }", "p = ((a));", "O x 5; O; ! q;", "p = ? + c;"]:
        assert dump(driver.parse(text, Recorder())) == dump(synthetic_reference(parser, text)), text
    for bad in ["p = ;", "S ;", "W ;", "% a;"]:
        with pytest.raises(lalr.Fallback):
            driver.parse(bad, Recorder())
        with pytest.raises(lark.exceptions.UnexpectedInput):
            parser.parse(bad)


def test_unsupported_configurations_are_refused():
    with pytest.raises(lalr.Unsupported):
        lalr.Driver(Lark(SYNTHETIC, parser="lalr", lexer="basic", propagate_positions=True), "start", Recorder)
    with pytest.raises(lalr.Unsupported):
        lalr.Driver(Lark(SYNTHETIC, parser="lalr", lexer="contextual"), "start", Recorder)
