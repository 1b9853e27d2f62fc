"""The fast driver's scanners (stvm/syntax/lalr.py) give Lark's tokens: the first-character split
leaves out only terminals that cannot start there, and whitespace is folded only when no terminal
can start with it."""

from __future__ import annotations

import re._parser as sre_parse
from pathlib import Path

import pytest
from lark import Lark

from stvm.syntax import lalr
from stvm.syntax import parser as P

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("regex, yes, no", [
    (r"(?i:abc)", "aA", "bx "),
    (r"[0-9][0-9_]*", "05", "a_ "),
    (r"(?i:[A-Za-z_][A-Za-z0-9_]*)", "aZ_", "0 ("),
    (r"(?:x)?y", "xy", "z"),
    (r"(?=\s)q|\(\*", "q(", "*"),
    (r"[^a]", "b ", ""),
    (r"\s+", " \t", ""),
    (r"(\\\\)?([A-Za-z_]\\)*[A-Za-z_]#", "\\aZ_", "#1"),
])
def test_may_start_with_says_yes_where_a_match_can_start(regex, yes, no):
    parsed = list(sre_parse.parse(regex))
    for c in yes:
        assert lalr._may_start_with(parsed, frozenset(c))[0], (regex, c)
    for c in no:
        assert not lalr._may_start_with(parsed, frozenset(c))[0], (regex, c)


def test_every_token_lark_makes_starts_with_a_character_its_terminal_may_start_with():
    lark = P._parser()
    terminals = {t.name: t for t in lark.terminals}
    texts = [p.read_text(encoding="utf-8") for p in sorted((ROOT / "st_src").rglob("*.st"))]
    seen = 0
    for text in texts:
        try:
            tokens = list(lark.lex(text, dont_ignore=True))
        except Exception:   # the basic lexer cannot take every file (contextual keywords): skip it
            continue
        for tok in tokens:
            if tok.type in terminals and ord(tok[0]) < 128:
                assert tok[0] in lalr._first_chars(terminals[tok.type]), (tok.type, tok)
                seen += 1
    assert seen > 1000


def test_whitespace_is_folded_for_st_and_not_where_a_terminal_starts_with_a_space():
    assert P._driver("start").skip_leading is not None
    grammar = 'start: (A | B)+\nA: "a"\nB.2: / b/\n%import common.WS\n%ignore WS\n'
    driver = lalr.Driver(Lark(grammar, parser="lalr", lexer="contextual", propagate_positions=True), "start", object)
    assert driver.skip_leading is None
    tree = driver.parse("a b a", object())
    assert [str(t) for t in tree.children] == ["a", " b", "a"]


def test_lexer_parts_are_what_larks_own_scanner_holds():
    """`_lexer_parts` gives every state's terminals and callbacks without compiling Lark's scanner;
    they must be exactly what that scanner, built afterwards, holds (same terminals, same order,
    same callback kinds, the keyword retyping equal)."""
    grammar = P.grammar_text()
    lark = Lark(grammar, **P.parser_options())       # a fresh one: no scanner built yet
    lexers = {id(b): b for b in lark.parser.lexer.lexers.values()}.values()
    for basic in lexers:
        assert basic._scanner is None
        terminals, callbacks = lalr._lexer_parts(basic)
        built = basic.scanner                           # Lark builds it now
        assert [t.name for t in terminals] == [t.name for t in built.terminals]
        assert sorted(callbacks) == sorted(basic.callback)
        for name, cb in callbacks.items():
            assert type(cb) is type(basic.callback[name])
            if isinstance(cb, lalr.UnlessCallback):
                for word in ("IF", "if", "END_IF", "x", "TRUE", "REAL", "FOR"):
                    assert cb.scanner.fullmatch(word) == basic.callback[name].scanner.fullmatch(word)
