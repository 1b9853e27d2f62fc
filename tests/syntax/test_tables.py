"""The parser tables shipped with stvm (stvm/syntax/tables.py) are current, used, and refused when stale."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from lark import Lark
from lark.exceptions import UnexpectedInput

from stvm.syntax import parser as P
from stvm.syntax import tables


ROOT = Path(__file__).resolve().parents[2]


def test_the_shipped_tables_are_current_and_parse_as_freshly_built_ones():
    shipped = tables.load(P.grammar_text(), P.parser_options())
    assert shipped is not None, ("stvm/syntax/st_tables.pickle is stale (grammar, parser options or Lark "
                                 "changed): rebuild it with `python -m stvm.stdlib.prebuilt`")
    fresh = Lark(P.grammar_text(), **P.parser_options())
    # (Lark numbers the states differently from one build to the next: compare what they parse)
    assert len(shipped.parser.parser.parser.parse_table.states) == len(fresh.parser.parser.parser.parse_table.states)
    texts = [p.read_text(encoding="utf-8") for p in sorted((ROOT / "st_src").rglob("*.st"))]
    assert texts
    for text in texts + ["PROGRAM P\nVAR x : INT; END_VAR\n{attribute 'a'} x := x + 1; (* c *)\nEND_PROGRAM\n"]:
        assert shipped.parse(text, start="start") == fresh.parse(text, start="start")
    for bad in ("PROGRAM P x := ; END_PROGRAM", "PROGRAM P IF x THEN END_PROGRAM"):
        errors = []
        for parser in (shipped, fresh):
            try:
                parser.parse(bad, start="start")
            except UnexpectedInput as exc:
                errors.append((type(exc), exc.line, exc.column, sorted(getattr(exc, "expected", ()))))
        assert len(errors) == 2 and errors[0] == errors[1]


def test_a_first_run_builds_no_tables(tmp_path):
    # a new, empty cache folder: the parser comes from the shipped file, so Lark neither builds
    # the tables nor writes them to the cache folder
    code = ("from stvm.syntax.parser import _parser, parse_text; _parser(); "
            "print(len(parse_text('PROGRAM P END_PROGRAM', 'p.st')[0].pous))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                            env={**os.environ, "STVM_CACHE_DIR": str(tmp_path / "cache")}, check=True)
    assert result.stdout.strip() == "1"
    assert not list(tmp_path.rglob("lark-tables-*"))


def test_the_pragma_callback_is_given_again_when_loading(monkeypatch):
    seen = []
    monkeypatch.setattr(P._PRAGMAS, "tokens", seen, raising=False)
    P._parser().parse("PROGRAM P {x} END_PROGRAM", start="start")
    assert [str(t) for t in seen] == ["{x}"]


def test_another_grammar_or_options_never_use_the_shipped_tables(tmp_path, monkeypatch):
    grammar, options = P.grammar_text(), P.parser_options()
    assert tables.load(grammar + "\n// edited\n", options) is None
    assert tables.load(grammar, {**options, "maybe_placeholders": False}) is None
    # a damaged file is not used either
    damaged = tmp_path / "st_tables.pickle"
    damaged.write_bytes(tables.FILE.read_bytes()[:1000])
    monkeypatch.setattr(tables, "FILE", damaged)
    assert tables.load(grammar, options) is None


def test_build_writes_a_file_that_load_accepts(tmp_path, monkeypatch):
    grammar = 'start: "a"+\n'
    options = {"parser": "lalr", "lexer": "contextual"}
    path = tables.build(grammar, options, tmp_path / "t.pickle")
    monkeypatch.setattr(tables, "FILE", path)
    loaded = tables.load(grammar, options)
    assert loaded is not None and loaded.parse("aaa").children == []
