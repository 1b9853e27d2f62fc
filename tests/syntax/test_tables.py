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
    assert shipped is not None, ("stvm/syntax/st_tables.json is stale (grammar, parser options or Lark "
                                 "changed): regenerate it with `python -m stvm.syntax.gen_tables`")
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
    damaged = tmp_path / "st_tables.json"
    damaged.write_bytes(tables.FILE.read_bytes()[:1000])
    monkeypatch.setattr(tables, "FILE", damaged)
    assert tables.load(grammar, options) is None


def test_the_text_form_round_trips_a_parser(tmp_path, monkeypatch):
    grammar = 'start: "a"+ b\nb: "b" | "c" b\n'
    options = {"parser": "lalr", "lexer": "contextual"}
    path = tmp_path / "t.json"
    path.write_text(tables.to_text(grammar, options, tables.serialise(Lark(grammar, **options))), encoding="ascii")
    monkeypatch.setattr(tables, "FILE", path)
    loaded = tables.load(grammar, options)
    assert loaded is not None and loaded.parse("aaccb") == Lark(grammar, **options).parse("aaccb")


def test_the_shipped_file_is_exactly_what_the_generator_writes():
    # text, reproducible: the generator's output for the grammar of this checkout is the file,
    # byte for byte (a grammar edit without regenerating, or a generator that varies, fails here)
    done = subprocess.run([sys.executable, "-m", "stvm.syntax.gen_tables", "--check"], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr


def test_the_canonical_numbering_does_not_depend_on_how_lark_built_the_table():
    grammar, options = P.grammar_text(), {k: v for k, v in P.parser_options().items() if k != "lexer_callbacks"}
    texts = set()
    for seed in ("1", "2"):
        code = ("import json,sys; from lark import Lark; from stvm.syntax import tables as T; "
                "g=sys.stdin.read(); o=json.loads(sys.argv[1]); "
                "sys.stdout.write(json.dumps(T._encode(T.serialise(Lark(g, **o)))))")
        done = subprocess.run([sys.executable, "-c", code, __import__("json").dumps(options)], input=grammar,
                              capture_output=True, text=True, cwd=ROOT, check=True,
                              env={**os.environ, "PYTHONHASHSEED": seed})
        texts.add(done.stdout)
    assert len(texts) == 1


def test_a_stale_install_builds_the_tables_once_into_the_signed_cache(tmp_path):
    # the shipped file does not match (here: missing); the first process builds and keeps the
    # tables as signed JSON, never as Lark's own pickle; the second reads them back
    code = ("from stvm.syntax import tables; tables.FILE = tables.FILE.with_name('missing.json'); "
            "from stvm.syntax.parser import _parser, parse_text; _parser(); "
            "print(len(parse_text('PROGRAM P END_PROGRAM', 'p.st')[0].pous))")
    env = {**os.environ, "STVM_CACHE_DIR": str(tmp_path / "cache"), "STVM_CACHE_KEY_FILE": str(tmp_path / "key")}
    for _ in range(2):
        result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env, check=True)
        assert result.stdout.strip() == "1"
    kept = list((tmp_path / "cache").rglob("lark-tables-*"))
    assert [p.suffix for p in kept] == [".json"]
    assert not list(tmp_path.rglob("*.pickle"))


def test_lark_is_a_release_stvm_was_tested_with():
    # stvm/syntax/lalr.py drives Lark's parse tables and imports two of its internals
    # (_create_unless, CallChain): a new Lark release must be tried before it is allowed
    # (pyproject.toml pins the range; widen both together)
    import lark
    assert lark.__version__ in {"1.3.0", "1.3.1"}, (
        f"lark {lark.__version__} is untested with stvm/syntax/lalr.py: run the syntax tests against it, "
        "then add it here and to pyproject.toml")
