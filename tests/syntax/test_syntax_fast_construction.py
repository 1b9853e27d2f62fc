"""The parser's fast paths build what the plain ones build: slot-setting `__init__` of frozen
nodes and spans, lazily positioned tokens, skipped pass-through callbacks."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import pytest
from lark import Token

from stvm.source import NO_SPAN, Span, fast_frozen_init
from stvm.syntax import lalr
from stvm.syntax import nodes as n
from stvm.syntax.parser import parse_text, parse_text_lark


def test_fast_init_keeps_signature_defaults_and_frozenness():
    span = Span("a.st", 1, 2, 3, 4)
    assert (span.file, span.line, span.column, span.end_line, span.end_column) == ("a.st", 1, 2, 3, 4)
    name = n.Name(("x",))
    assert name.rooted is False and name.span is NO_SPAN
    assert n.Name(("x",), True, span) == n.Name(parts=("x",), rooted=True, span=span)
    with pytest.raises(TypeError):
        n.Name()
    with pytest.raises(TypeError):
        n.Name(("x",), False, span, "extra")
    with pytest.raises(dataclasses.FrozenInstanceError):
        span.line = 5
    assert dataclasses.replace(name, rooted=True).rooted is True
    assert n.Name.__init__.__qualname__ == "Name.__init__"


def test_fast_init_leaves_classes_it_cannot_speed_up_alone():
    @dataclasses.dataclass(frozen=True)
    class Unslotted:
        x: int

    @dataclasses.dataclass(frozen=True, slots=True)
    class WithFactory:
        x: tuple = dataclasses.field(default_factory=tuple)

    for cls in (Unslotted, WithFactory):
        before = cls.__init__
        assert fast_frozen_init(cls) is cls and cls.__init__ is before


def test_spans_and_nodes_pickle_to_equal_values():
    span = Span("a.st", 1, 2, 3, 4)
    node = n.Binary("PLUS", n.Name(("a",), False, span), n.IntLiteral(1, span), span)
    back = pickle.loads(pickle.dumps(node, protocol=pickle.HIGHEST_PROTOCOL))
    assert back == node and back.span == span and back.left.span == span
    assert hash(pickle.loads(pickle.dumps(span))) == hash(span)


def test_lazy_token_positions_equal_eager_ones():
    text = "ab\ncd ef\n"
    lines = lalr.line_starts(text)
    tok = str.__new__(lalr.LazyToken, "ef")
    tok.type, tok.value, tok.start_pos, tok.end_pos, tok._lines = "IDENT", "ef", 6, 8, lines
    assert (tok.line, tok.column, tok.end_line, tok.end_column) == (2, 4, 2, 6)
    for plain in (tok.eager(), copy.deepcopy(tok)):
        assert type(plain) is Token and plain == "ef" and plain.type == "IDENT"
        assert (plain.line, plain.column, plain.end_line, plain.end_column) == (2, 4, 2, 6)
    unpickled = pickle.loads(pickle.dumps(tok))   # as Lark pickles a Token: type, text, start
    assert type(unpickled) is Token and (unpickled.type, unpickled.line, unpickled.column) == ("IDENT", 2, 4)


SOURCE = """FUNCTION_BLOCK FB
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT y : DINT; END_VAR
VAR a : ARRAY[0..3] OF INT; k : INT; END_VAR
y := a[1] + x * 2 - (3 MOD 2);
FOR k := 0 TO 3 DO a[k] := k; END_FOR;
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : FB; END_VAR
f(x := 1);
END_PROGRAM
"""


def test_fast_driver_spans_equal_larks_for_names_tokens_and_pass_through_rules():
    fast, fast_diags = parse_text(SOURCE, "m.st")
    slow, slow_diags = parse_text_lark(SOURCE, "m.st")
    assert fast == slow and fast_diags == slow_diags == []

    def spans(node):
        out = []
        for value in (node if isinstance(node, tuple) else (node,)):
            if dataclasses.is_dataclass(value) and not isinstance(value, Span):
                out.append((type(value).__name__, value.span if hasattr(value, "span") else None))
                for f in dataclasses.fields(value):
                    out += spans(getattr(value, f.name))
            elif isinstance(value, tuple):
                out += spans(value)
        return out

    assert spans(fast.pous) == spans(slow.pous)
    assert fast.pous[0].name_span == slow.pous[0].name_span == Span("m.st", 1, 16, 1, 18)


def test_walk_yields_every_node_and_name_uses_weights_loops():
    from stvm.syntax.walk import name_uses, walk
    fb = parse_text(SOURCE, "m.st")[0].pous[0]
    kinds = [type(x).__name__ for x in walk(fb.body)]
    assert kinds.count("Assign") == 2 and kinds.count("For") == 1 and kinds.count("Index") == 2
    assert all(dataclasses.is_dataclass(x) for x in walk(fb.body))
    # y, x, a once each outside the loop; inside FOR (bounds included) each use counts 10
    assert name_uses(fb.body) == {"y": 1, "a": 11, "x": 1, "k": 30}


def test_fast_nodes_pickle_and_copy_as_constructor_arguments():
    span = Span("a.st", 1, 2, 3, 4)
    call = n.Call(n.Name(("f",), False, span), (n.Argument("positional", None, n.IntLiteral(7, span), span),), span)
    assert n.Call.__reduce__.__qualname__ == "Call.__reduce__"
    # the constructor arguments with the span spelled out (no Span object to reduce and memoise)
    rebuild, args = call.__reduce__()
    assert rebuild is n._unpickled_Call and args == (call.callee, call.args, "a.st", 1, 2, 3, 4)
    assert rebuild(*args) == call and rebuild(*args).span == span and rebuild(*args).nid != call.nid
    # a span field elsewhere than last (POU has name_span after it) lands in its own place
    pou = parse_text("PROGRAM P\nEND_PROGRAM\n", "p.st")[0].pous[0]
    back = pickle.loads(pickle.dumps(pou, protocol=pickle.HIGHEST_PROTOCOL))
    assert back == pou and back.span == pou.span and back.name_span == pou.name_span
    # something other than a Span in the span slot pickles as plain constructor arguments
    odd = n.IntLiteral(1, None)
    assert odd.__reduce__() == (n.IntLiteral, (1, None))
    assert pickle.loads(pickle.dumps(odd)).span is None
    for back in (pickle.loads(pickle.dumps(call, protocol=pickle.HIGHEST_PROTOCOL)), copy.deepcopy(call),
                 copy.copy(call)):
        assert back == call and back.span == span and back.args[0].value.span == span
    unit = parse_text("PROGRAM P\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n", "p.st")[0]
    assert pickle.loads(pickle.dumps(unit, protocol=pickle.HIGHEST_PROTOCOL)) == unit
