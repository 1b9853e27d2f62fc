"""Parse ST text into `CompilationUnit`s (one per file), collecting syntax diagnostics.

Lark builds a parse tree (LALR, contextual lexer, positions on); one Transformer turns it into
the frozen dataclasses of `nodes`. Literal decoding ($ escapes, T#…, 16#…) happens here, so later
stages only see values.
"""

from __future__ import annotations

import math
import threading
from bisect import bisect_right
from dataclasses import replace
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Sequence

import lark
from lark import Lark, Token, Transformer, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from stvm.diagnostics import Diagnostic
from stvm.folders import content_name
from stvm.heap import collector_paused
from stvm.dialects import allows
from stvm.settings import DEFAULT_SETTINGS, Dialect, DoubleQuoteStrings, SysmacSettings
from stvm.source import read_source
from stvm.syntax import nodes as n
from stvm.syntax import lalr, tables
from stvm.syntax.lalr import Meta2 as _Meta2

_GRAMMAR_FILE = "st.lark"


def parser_options() -> dict:
    """The options stvm's Lark parser is built with (also the key of the shipped tables)."""
    return dict(parser="lalr", lexer="contextual", propagate_positions=True,
                start=["start", "expression"], maybe_placeholders=True,
                lexer_callbacks={"PRAGMA": _pragma_seen})


@lru_cache(maxsize=None)
def _parser(start: str = "start") -> Lark:
    grammar = grammar_text()
    options = parser_options()
    # Building the LALR tables takes about a second: stvm ships them (syntax/tables.py, checked
    # against the grammar, the options and Lark's version)
    shipped = tables.load(grammar, options)
    if shipped is not None:
        return shipped
    return _built_parser(grammar, options)


def _built_parser(grammar: str, options: dict) -> Lark:
    """A stale shipped file (an edited grammar, another Lark): Lark builds the tables, kept for the
    next run as the same JSON text in stvm's signed cache. Never Lark's own `cache=`: that file is
    a pickle Lark partly unpickles before checking its hash, in a folder another user may write."""
    from stvm.cache import SignedCache   # lazy: only a stale install gets here
    cache = SignedCache()
    name = content_name("lark-tables", grammar, lark.__version__, _GRAMMAR_FILE, suffix=".json")
    held = cache.get(name)
    if held is not None:
        parser = tables.from_text(held.decode("ascii", "replace"), grammar, options)
        if parser is not None:
            return parser
    parser = Lark(grammar, **options)
    cache.put(name, tables.to_text(grammar, options, tables.serialise(parser)).encode("ascii"))
    return parser


_PRAGMAS = threading.local()   # the `{…}` tokens the lexer dropped during the current parse_text


def _pragma_seen(token: Token) -> Token:
    seen = getattr(_PRAGMAS, "tokens", None)
    if seen is not None:
        seen.append(token)
    return token


def grammar_text() -> str:
    return resources.files("stvm.syntax").joinpath(_GRAMMAR_FILE).read_text(encoding="utf-8")


from stvm.syntax.literals import (LiteralError, check_digit_separators, decode_date, decode_dt, decode_int, decode_string,  # noqa: F401
                                  decode_time, decode_tod, decode_wstring)


# ---- parse tree → nodes ------------------------------------------------------------------------

def _span_of(file: str, meta) -> n.Span:
    if getattr(meta, "empty", False) or not hasattr(meta, "line"):
        return n.Span(file, 0, 0, 0, 0)
    return n.Span(file, meta.line, meta.column, meta.end_line, meta.end_column)


def _tok_span(file: str, tok: Token) -> n.Span:
    return n.Span(file, tok.line, tok.column, tok.end_line or tok.line, tok.end_column or tok.column + len(tok))


# binding strength of each binary operator token (higher binds tighter)
_PRECEDENCE = {"OR": 1, "OR_ELSE": 1, "XOR": 2, "AND": 3, "AND_THEN": 3, "AMP": 3, "EQ": 4, "NE": 4, "LT": 5, "GT": 5, "LE": 5, "GE": 5,
               "PLUS": 6, "MINUS": 6, "STAR": 7, "SLASH": 7, "MOD": 7, "POW": 8}


def _int_bound(expr):
    """A subrange bound: its int when it is a (signed) integer literal, else the expression."""
    if isinstance(expr, n.IntLiteral):
        return expr.value
    if isinstance(expr, n.Unary) and expr.op in ("MINUS", "PLUS") and isinstance(expr.operand, n.IntLiteral):
        return -expr.operand.value if expr.op == "MINUS" else expr.operand.value
    return expr


class _Modifier(str):
    """PUBLIC, PRIVATE, ABSTRACT, FINAL, … in a POU, METHOD or PROPERTY header."""


def _long_form(items, short: str, long: str) -> str:
    """The literal's type from its prefix: `LTIME#…` / `LT#…` (etc.) are the long form."""
    return long if str(items[0]).upper().startswith("L") else short


class _ToNodes:
    """The node-building callbacks, one per grammar rule (or alias), each taking (meta, items).

    `lalr.Driver` calls them at reduction time (meta is then an `lalr.Meta2`); on the fallback
    path `_FromTree` calls them over Lark's tree (meta is Lark's Meta). Either way, get a span
    with `self._s(meta)`. Literal errors become diagnostics, not exceptions."""

    def __init__(self, file: str, settings: SysmacSettings, diagnostics: list[Diagnostic]) -> None:
        self.namespace_names: list[tuple[str, n.Span]] = []
        self.member_bases: set[str] = set()
        self.file = file
        self.settings = settings
        self.diagnostics = diagnostics
        self._line: tuple = (None, 0, 0, 0)   # (line starts, offsets lo, hi, line number) of _s's last line

    def _s(self, meta) -> n.Span:
        if meta.__class__ is _Meta2:
            start, end, lines = meta
            if start < 0:
                return n.Span(self.file, 0, 0, 0, 0)
            # the line the previous span started on, offsets lo..hi-1: most nodes start on the
            # line the one before them started on, so most spans need no search
            known, lo, hi, li = self._line
            if start >= hi or start < lo or known is not lines:
                li = bisect_right(lines, start)   # (lines[li] exists: the last entry is past the text)
                lo, hi = lines[li - 1], lines[li]
                if li < len(_INTS):   # one int object per line number, shared by all spans (memory; see _intern_lines)
                    li = _INTS[li]
                self._line = (lines, lo, hi, li)
            if end < hi:   # most spans end on the line they start on
                return n.Span(self.file, li, start - lo + 1, li, end - lo + 1)
            lj = bisect_right(lines, end, li)
            if lj < len(_INTS):
                lj = _INTS[lj]
            return n.Span(self.file, li, start - lo + 1, lj, end - lines[lj - 1] + 1)
        return _span_of(self.file, meta)

    def _ts(self, tok: Token) -> n.Span:
        if tok.__class__ is lalr.LazyToken:   # the fast driver's: offsets, lines found here
            lines = tok._lines
            start, end = tok.start_pos, tok.end_pos
            li = bisect_right(lines, start)
            lj = li if end < lines[li] else bisect_right(lines, end, li)
            return n.Span(self.file, li, start - lines[li - 1] + 1, lj, end - lines[lj - 1] + 1)
        return _tok_span(self.file, tok)

    # -- top level
    def start(self, meta, items):
        return list(items)

    def namespace(self, meta, items):
        path = tuple(items[0])
        return ("namespace", path, items[1:])

    def name_path(self, meta, items):
        self.namespace_names += [(str(t), self._ts(t)) for t in items]
        return [str(t) for t in items]

    def pragmas(self, meta, items):
        return tuple(str(t)[1:-1].strip() for t in items)

    def pou(self, meta, items):
        pragmas, kind, *rest = items
        modifiers = []
        while isinstance(rest[0], _Modifier):
            modifiers.append(str(rest.pop(0)))
        name, ret, extends, implements, *rest = rest
        end = rest[-1]
        body, methods, properties = rest[-2]
        blocks = tuple(rest[:-2])
        return n.POU(kind, str(name), (), ret, blocks, body, pragmas, self._s(meta), end,
                     modifiers=tuple(modifiers), extends=extends or (), implements=implements or (),
                     methods=methods, properties=properties, name_span=self._ts(name))

    def pou_body(self, meta, items):
        statements = tuple([s for s in items if isinstance(s, n.Statement) and not isinstance(s, n.Empty)])
        methods = tuple([m for m in items if isinstance(m, n.Method)])
        properties = tuple([m for m in items if isinstance(m, n.Property)])
        return statements, methods, properties

    def extends_clause(self, meta, items):
        return tuple(items)

    def implements_clause(self, meta, items):
        return tuple(items)

    def modifier(self, meta, items):
        return _Modifier(str(items[0]).upper())

    def _member_head(self, items):
        pragmas, *rest = items
        modifiers = []
        while isinstance(rest[0], _Modifier):
            modifiers.append(str(rest.pop(0)))
        return pragmas, tuple(modifiers), rest

    def method_decl(self, meta, items):
        pragmas, modifiers, rest = self._member_head(items)
        name, ret, *rest = rest
        body = rest[-1]
        return n.Method(str(name), modifiers, ret, tuple(rest[:-1]), body, pragmas, self._s(meta), self._ts(name))

    def property_decl(self, meta, items):
        pragmas, modifiers, rest = self._member_head(items)
        name, type_spec, *rest = rest
        blocks = tuple(x for x in rest if isinstance(x, n.VarBlock))
        getter = next((x for x in rest if isinstance(x, n.Accessor) and x.kind == "GET"), None)
        setter = next((x for x in rest if isinstance(x, n.Accessor) and x.kind == "SET"), None)
        return n.Property(str(name), modifiers, type_spec, blocks, getter, setter, pragmas, self._s(meta),
                          self._ts(name))

    def property_accessor(self, meta, items):
        word, end = str(items[0]).upper(), str(items[-1]).upper()
        if word not in ("GET", "SET"):
            self._error(f"syntax error: unexpected '{items[0]}'; expected GET, SET or END_PROPERTY", self._ts(items[0]),
                        "E001")
        elif end != "END_" + word:
            self._error(f"{word} ends with END_{word}, not {end}", self._ts(items[-1]), "E001")
        return n.Accessor(word if word in ("GET", "SET") else "GET", tuple(items[1:-2]), items[-2], self._s(meta))

    def interface(self, meta, items):
        pragmas, name, extends, *members = items
        methods = tuple(m for m in members if isinstance(m, n.Method))
        properties = tuple(m for m in members if isinstance(m, n.Property))
        return n.POU("INTERFACE", str(name), (), None, (), (), pragmas, self._s(meta), self._s(meta),
                     extends=extends or (), methods=methods, properties=properties, name_span=self._ts(name))

    def pou_kind(self, meta, items):
        return str(items[0].type)

    @lalr.passes_child
    def return_type(self, meta, items):
        return items[0]

    def end_pou(self, meta, items):
        return self._s(meta)

    def var_block(self, meta, items):
        kind = items[0]
        quals = tuple([q for q in items[1:] if isinstance(q, str)])
        decls = tuple([d for d in items[1:] if isinstance(d, n.VarDecl)])
        return n.VarBlock(kind, quals, decls, self._s(meta))

    def var_kind(self, meta, items):
        return str(items[0].type)

    def var_qualifier(self, meta, items):
        word = str(items[0]).upper()
        if word == "PERSISTENT" and not allows(self.settings.dialect, "persistent"):
            self._error(f"PERSISTENT is a CODESYS/TwinCAT qualifier, not one of {self.settings.dialect.value} "
                        "(use RETAIN, or --dialect codesys|twincat)", self._s(meta), "E009")
        return word

    def var_decl(self, meta, items):
        names = items[0]
        rest = [x for x in items[1:] if x is not None and not (isinstance(x, tuple) and x and x[0] == "location")]
        type_spec = rest[0]
        init = rest[1] if len(rest) > 1 else None
        return n.VarDecl(names, type_spec, init, self._s(meta))

    def fb_args_var_decl(self, meta, items):
        names = items[0]
        rest = [x for x in items[1:] if not (isinstance(x, tuple) and x and x[0] == "location")]
        name = rest[0]
        args = tuple(a for a in rest[1:] if isinstance(a, n.Argument))
        init = next((x for x in rest[1:] if x is not None and not isinstance(x, n.Argument)), None)
        type_spec = n.NamedTypeSpec(name.parts, name.rooted, name.span)
        return n.VarDecl(names, type_spec, init, self._s(meta), args)

    def ident_list(self, meta, items):
        return tuple([(str(t), self._ts(t)) for t in items])

    def location(self, meta, items):
        return ("location", str(items[0]))

    def global_block(self, meta, items):
        return n.GlobalVars(items[0], (), self._s(meta))

    # -- types
    def type_block(self, meta, items):
        return ("types", list(items))

    def type_decl(self, meta, items):
        return n.TypeDecl(str(items[0]), (), items[1], self._s(meta))

    def struct_spec(self, meta, items):
        return n.StructDecl(tuple(items), self._s(meta))

    def union_spec(self, meta, items):
        return n.UnionDecl(tuple(items), self._s(meta))

    def field_decl(self, meta, items):
        return n.VarDecl(items[0], items[1], items[2], self._s(meta))

    def enum_spec(self, meta, items):
        base = None
        default = None
        members = []
        for item in items:
            if isinstance(item, tuple) and item and item[0] == "member":
                members.append(item[1:])
            elif isinstance(item, tuple) and item and item[0] == "elem":
                base = item[1]
            elif isinstance(item, n.Name):   # the leading base type (a qualified_name, see st.lark)
                base = "\\".join(item.parts)
            elif isinstance(item, Token):
                default = str(item)
        return n.EnumDecl(tuple(members), base, default, self._s(meta))

    def enum_member(self, meta, items):
        value = items[1] if len(items) > 1 else None
        return ("member", str(items[0]), value, self._ts(items[0]))

    def signed_int(self, meta, items):
        sign = -1 if len(items) == 2 and str(items[0]) == "-" else 1
        lit = items[-1]
        return sign * lit.value

    def elementary_name(self, meta, items):
        return ("elem", str(items[0]))

    def alias_spec(self, meta, items):
        return n.AliasDecl(items[0], items[1] if len(items) > 1 else None, self._s(meta))

    def type_name(self, meta, items):
        name = items[0]
        return n.NamedTypeSpec(name.parts, name.rooted, name.span)

    def string_spec(self, meta, items):
        wide = str(items[0]).upper().startswith("W")
        return n.StringTypeSpec(items[1], wide, self._s(meta))

    def array_spec(self, meta, items):
        return n.ArrayTypeSpec(tuple(items[:-1]), items[-1], self._s(meta))

    def bounds(self, meta, items):
        return (items[0], items[1])

    def any_bounds(self, meta, items):
        return None

    def subrange_spec(self, meta, items):
        # a literal bound is kept as its int; another constant expression (TwinCAT:
        # `UINT(0..GVL_Param.Max)`) is left to the checker to fold
        low, high = (_int_bound(x) for x in items[1:3])
        return n.SubrangeTypeSpec("\\".join(items[0].parts), low, high, self._s(meta))

    def ref_spec(self, meta, items):
        return n.RefTypeSpec(items[-1], "REF_TO", self._s(meta))

    def pointer_spec(self, meta, items):
        return n.RefTypeSpec(items[-1], "POINTER", self._s(meta))

    def reference_spec(self, meta, items):
        return n.RefTypeSpec(items[-1], "REFERENCE", self._s(meta))

    def initializer(self, meta, items):
        return n.ExprInit(items[0], self._s(meta))

    def array_init(self, meta, items):
        return n.ArrayInit(tuple(items), self._s(meta))

    def array_init_item(self, meta, items):
        return (1, items[0])

    def repeat_init(self, meta, items):
        return (decode_int(str(items[0])), items[1] if len(items) > 1 else None)

    def struct_init(self, meta, items):
        return n.StructInit(tuple(items), self._s(meta))

    def struct_init_item(self, meta, items):
        return (str(items[0]), items[1])

    # -- configuration
    def configuration(self, meta, items):
        name = str(items[0])
        globals_ = [x.block for x in items[1:] if isinstance(x, n.GlobalVars)]
        resources_ = [x for x in items[1:] if isinstance(x, n.Resource)]
        loose_tasks = tuple(x for x in items[1:] if isinstance(x, n.TaskDecl))
        loose_programs = tuple(x for x in items[1:] if isinstance(x, n.ProgramConfig))
        if loose_tasks or loose_programs:
            resources_.insert(0, n.Resource(name, (), loose_tasks, loose_programs, self._s(meta)))
        return n.Configuration(name, tuple(globals_), tuple(resources_), self._s(meta))

    def resource(self, meta, items):
        name = str(items[0])
        rest = [x for x in items[1:] if not isinstance(x, Token) and x is not None]
        return n.Resource(name, tuple(x.block for x in rest if isinstance(x, n.GlobalVars)),
                          tuple(x for x in rest if isinstance(x, n.TaskDecl)),
                          tuple(x for x in rest if isinstance(x, n.ProgramConfig)), self._s(meta))

    def task_decl(self, meta, items):
        return n.TaskDecl(str(items[0]), tuple(items[1:]), self._s(meta))

    def task_param(self, meta, items):
        return (str(items[0]).upper(), items[1])

    def program_config(self, meta, items):
        instance = str(items[0])
        task = str(items[1]) if items[1] is not None else None
        type_name = items[2].parts
        args = tuple(a for a in items[3:] if isinstance(a, n.Argument))
        return n.ProgramConfig(instance, task, type_name, args, self._s(meta))

    # -- statements
    def statement_list(self, meta, items):
        return tuple([s for s in items if not isinstance(s, n.Empty)])

    def assignment(self, meta, items):
        return n.Assign(items[0], items[1], self._s(meta))

    def assign_chain(self, meta, items):
        """`target := value` inside an expression, a condition or a chained assignment."""
        span = self._s(meta)
        if not allows(self.settings.dialect, "assignment_expression"):
            self._error("an assignment used as an expression ('x := (y := v)', 'IF (i := i + 1) = n') is "
                        f"CODESYS/TwinCAT syntax, not {self.settings.dialect.value} (use --dialect twincat|codesys)",
                        span, "E009")
        return n.AssignExpr(items[0], items[1], span)

    def ref_assignment(self, meta, items):
        return n.RefAssign(items[0], items[2], self._s(meta))

    def call_statement(self, meta, items):
        return n.CallStatement(items[0], self._s(meta))

    def exit_statement(self, meta, items):
        return n.Exit(self._s(meta))

    def continue_statement(self, meta, items):
        return n.Continue(self._s(meta))

    def return_statement(self, meta, items):
        return n.Return(self._s(meta))

    def empty_statement(self, meta, items):
        return n.Empty(self._s(meta))

    def if_statement(self, meta, items):
        branches = [(items[0], items[1])]
        else_body = None
        for item in items[2:]:
            if isinstance(item, tuple) and len(item) == 3 and item[0] == "elsif":
                branches.append((item[1], item[2]))
            elif isinstance(item, tuple) and len(item) == 2 and item[0] == "else":
                else_body = item[1]
        return n.If(tuple(branches), else_body, self._s(meta))

    def elsif_clause(self, meta, items):
        return ("elsif", items[0], items[1])

    def else_clause(self, meta, items):
        return ("else", items[0])

    def case_statement(self, meta, items):
        selector = items[0]
        elements = []
        else_body = None
        for item in items[1:]:
            if isinstance(item, tuple) and item[0] == "else":
                else_body = item[1]
            elif item is not None:
                elements.append(item)
        return n.Case(selector, tuple(elements), else_body, self._s(meta))

    def case_element(self, meta, items):
        return (tuple(items[:-1]), items[-1])

    def case_label(self, meta, items):
        return n.CaseLabel(self._label_value(items[0], meta), None, self._s(meta))

    def case_range(self, meta, items):
        return n.CaseLabel(self._label_value(items[0], meta), self._label_value(items[1], meta), self._s(meta))

    def _label_value(self, value, meta):
        if isinstance(value, int):
            return n.IntLiteral(value, self._s(meta))
        return value

    def case_name(self, meta, items):
        tok = items[0]
        first, *rest = str(tok).split(".")
        if rest:   # `Enum.member:`, `Lib.Enum.member:` (CODESYS/TwinCAT)
            span = self._ts(tok)
            self.member_bases.add(first.lower())
            expr = n.Name((first,), False, n.Span(self.file, span.line, span.column, span.line,
                                                  span.column + len(first)))
            for part in rest:
                expr = n.Member(expr, part, span)
            return expr
        return n.Name((str(tok),), False, self._ts(tok))

    def case_hash(self, meta, items):
        return self._hash(items[0])

    def for_statement(self, meta, items):
        var, start, end, step, body = items
        return n.For(var, start, end, step, body, self._s(meta))

    def while_statement(self, meta, items):
        return n.While(items[0], items[1], self._s(meta))

    def repeat_statement(self, meta, items):
        return n.Repeat(items[0], items[1], self._s(meta))

    # -- expressions
    @lalr.passes_child
    def binary_op(self, meta, items):
        return items[0]

    def expression(self, meta, items):
        """Precedence climbing over the flat chain [operand, op, operand, …]."""
        if len(items) == 3:   # the common case, one operator: what climb() below makes of it
            left, op, right = items
            span = n.Span(self.file, left.span.line, left.span.column, right.span.end_line, right.span.end_column)
            return n.Binary(str(op.type), left, right, span)
        operands = items[0::2]
        ops = items[1::2]
        pos = 0

        def climb(min_level: int):
            nonlocal pos
            left = operands[pos]
            while pos < len(ops) and _PRECEDENCE[ops[pos].type] >= min_level:
                op = ops[pos]
                level = _PRECEDENCE[op.type]
                pos += 1
                right = climb(level + 1)   # left-associative: the right side binds tighter
                span = n.Span(self.file, left.span.line, left.span.column, right.span.end_line, right.span.end_column)
                left = n.Binary(str(op.type), left, right, span)
            return left

        tree = climb(0)
        del climb   # the closure refers to itself: left alone, each expression would be cyclic garbage
        return tree


    init_expression = expression   # an initializer's expression (st.lark): the same chain
    def unary(self, meta, items):
        op, operand = items
        return n.Unary(str(op.type), operand, self._s(meta))

    @lalr.passes_child
    def name(self, meta, items):
        return items[0]

    def dotted_name(self, meta, items):
        """`Library.Name` in EXTENDS, IMPLEMENTS or a type (CODESYS/TwinCAT library namespaces):
        the same parts as `Library\\Name`; semantics/checker.py resolves it (lookup_*_key)."""
        return n.Name(tuple(str(t) for t in items), False, self._s(meta))

    def qualified_name(self, meta, items):
        if len(items) == 1:                     # the common case: one IDENT
            return n.Name((items[0].value,), False, self._s(meta))
        rooted = bool(items) and isinstance(items[0], Token) and items[0].type == "ROOT_SEP"
        parts = tuple(str(t) for t in items if isinstance(t, Token) and t.type == "IDENT")
        return n.Name(parts, rooted, self._s(meta))

    def member(self, meta, items):
        base = items[0]
        if type(base) is n.Name:   # `X.y` with a plain name: maybe a GVL or an enum (semantics/qualified.py)
            self.member_bases.add(base.parts[-1].lower())
        return n.Member(base, str(items[1]), self._s(meta))

    def bit_access(self, meta, items):
        return n.BitAccess(items[0], int(str(items[1]).replace("_", "")), self._s(meta))

    def index(self, meta, items):
        return n.Index(items[0], tuple(items[1:]), self._s(meta))

    def call(self, meta, items):
        args = []
        for item in items[1:]:
            if isinstance(item, n.Argument):
                args.append(item)
            elif item is not None:   # COMMA_END, or an unbound output (formal_output_empty)
                self._call_extra(item)
        return n.Call(items[0], tuple(args), self._s(meta))

    def _call_extra(self, item) -> None:
        """A trailing comma or an unbound output (`Q=> ,`): TwinCAT/CODESYS call syntax, dropped
        there (stvm/dialects.py `call_syntax`), an error elsewhere."""
        if allows(self.settings.dialect, "call_syntax"):
            return
        if isinstance(item, tuple):
            what, span = f"an output with nothing bound ('{item[1]} =>')", item[2]
        else:
            what, span = "a comma before ')'", self._ts(item)
        self._error(f"{what} is TwinCAT/CODESYS call syntax, not {self.settings.dialect.value} "
                    "(use --dialect twincat|codesys)", span, "E009")

    def formal_output_empty(self, meta, items):
        return ("empty_output", str(items[0]), self._s(meta))

    def set_reset_assignment(self, meta, items):
        """`x S= c;` / `x R= c;` (CODESYS, TwinCAT): IF c THEN x := TRUE (FALSE); END_IF."""
        span = self._s(meta)
        setting = str(items[1]).upper().startswith("S")
        if not allows(self.settings.dialect, "set_reset_assign"):
            self._error(f"'{str(items[1]).upper()}' is CODESYS/TwinCAT syntax, not "
                        f"{self.settings.dialect.value} (use --dialect twincat|codesys)", span, "E009")
        store = n.Assign(items[0], n.BoolLiteral(setting, span), span)
        return n.If(((items[2], (store,)),), None, span)

    def partial_access(self, meta, items):
        text = str(items[1])
        index = int(text[2:])
        letter = text[1].upper()
        if letter == "X":
            return n.BitAccess(items[0], index, self._s(meta))
        return n.PartialAccess(items[0], index, self._s(meta), width={"B": 8, "W": 16, "D": 32}[letter])

    def keyword_call(self, meta, items):
        # MOD(a, b), AND(a, b, …): the operators' function forms call the stdlib's `__MOD`, `__AND`
        word = items[0]
        callee = n.Name(("__" + str(word).upper(),), False, _tok_span(self.file, word))
        return n.Call(callee, tuple([a for a in items[1:] if a is not None]), self._s(meta))

    def deref(self, meta, items):
        return n.Deref(items[0], self._s(meta))

    def formal_input(self, meta, items):
        return n.Argument("input", str(items[0]), items[1], self._s(meta))

    def formal_output(self, meta, items):
        return n.Argument("output", str(items[0]), items[1], self._s(meta))

    def formal_output_not(self, meta, items):
        return n.Argument("output_not", str(items[1]), items[2], self._s(meta))

    def positional(self, meta, items):
        return n.Argument("positional", None, items[0], self._s(meta))

    # -- literals
    def _error(self, message: str, span: n.Span, code: str):
        self.diagnostics.append(Diagnostic.error(message, span, code))

    def int_literal(self, meta, items):
        text = str(items[0])
        # INTEGER is /[0-9][0-9_]*/: int() takes it as it is unless it has a `_` or is long
        if "_" not in text and len(text) <= 20:
            return n.IntLiteral(int(text), self._s(meta))
        return self.based_literal(meta, items)

    def based_literal(self, meta, items):
        try:
            value = decode_int(str(items[0]))
        except LiteralError as exc:   # a `1__0`, or thousands of digits (an error, not exit 70)
            self._error(str(exc), self._s(meta), "E008")
            value = 0
        return n.IntLiteral(value, self._s(meta))

    def real_literal(self, meta, items):
        raw = str(items[0])
        text = raw.replace("_", "")
        try:
            if "_" in raw:
                check_digit_separators(raw.split("e")[0].split("E")[0].replace(".", ""))
            value = float(text)
            if not math.isfinite(value):
                raise LiteralError(f"REAL literal {text[:40]!r} is out of range: LREAL holds at most "
                                   f"±1.7976931348623157E308")
        except LiteralError as exc:
            self._error(str(exc), self._s(meta), "E008")
            value = 0.0
        return n.RealLiteral(value, text, self._s(meta))

    def true_literal(self, meta, items):
        return n.BoolLiteral(True, self._s(meta))

    def false_literal(self, meta, items):
        return n.BoolLiteral(False, self._s(meta))

    def _literal(self, meta, items, type_name, decoder):
        text = str(items[0])
        try:
            return n.TimeLiteral(type_name, decoder(text), self._s(meta))
        except (LiteralError, ValueError) as exc:
            self._error(str(exc) if isinstance(exc, LiteralError) else f"malformed literal {text!r}", self._s(meta),
                        "E008")
            return n.TimeLiteral(type_name, 0, self._s(meta))

    # the long forms (LT#, LTIME#, LDATE#, LD#, LTOD#, LTIME_OF_DAY#, LDT#, LDATE_AND_TIME#) are
    # the IEC ed. 3 64-bit types; DATE_AND_TIME# starts with D too, so the prefix decides
    def time_literal(self, meta, items):
        type_name = _long_form(items, "TIME", "LTIME")
        if allows(self.settings.dialect, "unsigned_time"):   # TwinCAT/CODESYS: 0..2^32-1 ms, 0..2^64-1 ns
            return self._literal(meta, items, type_name, lambda text: decode_time(text, type_name))
        return self._literal(meta, items, type_name, decode_time)

    def date_literal(self, meta, items):
        return self._literal(meta, items, _long_form(items, "DATE", "LDATE"), decode_date)

    def tod_literal(self, meta, items):
        return self._literal(meta, items, _long_form(items, "TIME_OF_DAY", "LTIME_OF_DAY"), decode_tod)

    def dt_literal(self, meta, items):
        return self._literal(meta, items, _long_form(items, "DATE_AND_TIME", "LDATE_AND_TIME"), decode_dt)

    def hash_literal(self, meta, items):
        return self._hash(items[0])

    def _hash(self, tok: Token) -> n.HashLiteral:
        text = str(tok)
        prefix, _, value = text.rpartition("#") if text.count("#") == 1 else (text.split("#", 1)[0], "#", text.split("#", 1)[1])
        rooted = prefix.startswith("\\\\")
        parts = tuple(p for p in prefix.lstrip("\\").split("\\") if p)
        return n.HashLiteral(parts, rooted, value, self._ts(tok))

    def string_literal(self, meta, items):
        text = str(items[0])
        span = self._s(meta)
        if text.startswith('"') and self.settings.dialect is not Dialect.SYSMAC:
            return self._wstring_literal(text, span)
        try:
            value, _ = decode_string(text, self.settings)
        except LiteralError as exc:
            self._error(str(exc), span, "E008")
            value = b""
        double = text.startswith('"')
        if double:
            if self.settings.double_quote_strings is DoubleQuoteStrings.ERROR:
                self._error('double-quoted text is a WSTRING; write STRING literals in single quotes', span, "E009")
            else:
                self.diagnostics.append(Diagnostic.warning(
                    "double-quoted string literal accepted as STRING (Sysmac `double_quote_strings`)", span, "W003"))
        return n.StringLiteral(value, double, span)

    def _wstring_literal(self, text: str, span) -> n.StringLiteral:
        """IEC: double-quoted text is a WSTRING literal; its value is a `str` of UTF-16 code units
        (Sysmac, which has no WSTRING, takes it as a STRING: `double_quote_strings`)."""
        try:
            value = decode_wstring(text, self.settings)
        except LiteralError as exc:
            self._error(str(exc), span, "E008")
            value = ""
        return n.StringLiteral(value, True, span)


def _collect(file: str, items: list, namespace: tuple[str, ...], out: dict[str, list]) -> None:
    for item in items:
        if isinstance(item, n.POU):
            out["pous"].append(replace(item, namespace=namespace) if namespace else item)
        elif isinstance(item, n.GlobalVars):
            out["globals"].append(n.GlobalVars(item.block, namespace, item.span))
        elif isinstance(item, n.Configuration):
            out["configurations"].append(item)
        elif isinstance(item, tuple) and item[0] == "types":
            for decl in item[1]:
                out["types"].append(n.TypeDecl(decl.name, namespace, decl.body, decl.span))
        elif isinstance(item, tuple) and item[0] == "namespace":
            _collect(file, item[2], namespace + tuple(item[1]), out)


_FRIENDLY = {
    "SEMICOLON": "';'", "IDENT": "a name", "COLON": "':'", "LPAR": "'('", "RPAR": "')'",
    "LSQB": "'['", "RSQB": "']'", "COMMA": "','", "DOT": "'.'", "EQ": "'='", "INTEGER": "a number",
    "STRING_LITERAL": "a string", "CASE_NAME": "a case label",
}
# tokens that may continue an expression: noise in "expected …" lists when a ';' or keyword fits
_CONTINUATIONS = {"PLUS", "MINUS", "STAR", "SLASH", "MOD", "POW", "AND", "AMP", "OR", "XOR", "AND_THEN", "OR_ELSE", "EQ", "NE",
                  "LT", "GT", "LE", "GE", "DOT", "LSQB", "LPAR", "CIRCUMFLEX", "NS_SEP"}


def _expected_text(expected: set[str]) -> str:
    """A short, readable "; expected …" for a syntax error."""
    terms = set(expected)
    if terms - _CONTINUATIONS:
        dropped = bool(terms & _CONTINUATIONS)
        terms -= _CONTINUATIONS
    else:
        dropped = False
    names = []
    for term in sorted(terms, key=lambda x: (x != "SEMICOLON", x)):
        if term.startswith("__ANON"):
            names.append("':='" if term == "__ANON_0" else term)
            continue
        if term.startswith("_") or term == "$END":
            continue
        names.append(_FRIENDLY.get(term, term))
    if not names:
        return ""
    if len(names) > 6:
        names = names[:6] + ["…"]
    return "; expected " + ", ".join(names) + (" or an operator" if dropped else "")


def _syntax_diagnostic(file: str, exc: UnexpectedInput) -> Diagnostic:
    if isinstance(exc, UnexpectedToken):
        tok = exc.token
        expected = set(exc.expected)
        parser_state = getattr(exc, "interactive_parser", None)
        if parser_state is not None:
            # LALR lookahead sets are merged across contexts; ask the parser what really fits here
            try:
                expected = set(parser_state.accepts()) or expected
            except Exception:  # accepts() replays the parser; never let it hide the real error
                pass
        if tok.type == "$END":
            span = n.Span(file, exc.line if exc.line > 0 else 1, max(exc.column, 1), exc.line, exc.column + 1)
            return Diagnostic.error("unexpected end of file" + _expected_text(expected), span, "E001")
        span = _tok_span(file, tok)
        return Diagnostic.error(f"syntax error: unexpected '{tok}'" + _expected_text(expected), span, "E001")
    if isinstance(exc, UnexpectedCharacters):
        span = n.Span(file, exc.line, exc.column, exc.line, exc.column + 1)
        char = exc.char
        if char in "'\"":
            return Diagnostic.error("unterminated or malformed string literal", span, "E002")
        return Diagnostic.error(f"syntax error: unexpected character {char!r}", span, "E001")
    if isinstance(exc, UnexpectedEOF):
        return Diagnostic.error("unexpected end of file", n.Span(file, 1, 1, 1, 2), "E001")
    return Diagnostic.error(f"syntax error: {exc}", n.Span(file, 1, 1, 1, 2), "E001")


_MAX_RECOVERED_ERRORS = 20


def _missing_semicolon_recovery(file: str, recovered: list[Diagnostic]):
    """Lark `on_error` handler for the one recovery that is certain: a missing ';'.

    When ';' is what the parser can take and the offending token fits right after it, the error
    is reported ("expected ';'") and parsing goes on, so one run shows every missing semicolon.
    Any other syntax error stops the parse (guessing there would report errors that are not
    there)."""
    def on_error(exc) -> bool:
        if not isinstance(exc, UnexpectedToken) or len(recovered) >= _MAX_RECOVERED_ERRORS:
            return False
        parser_state = exc.interactive_parser
        try:
            if "SEMICOLON" not in parser_state.accepts():
                return False
            trial = parser_state.copy()
            trial.feed_token(Token("SEMICOLON", ";"))
            accepted = trial.accepts()
            token = exc.token
            # the contextual lexer typed a keyword it did not expect here as a name (END_VAR
            # after a missing ';'); after the ';' it is the keyword again
            if token.type == "IDENT" and token.value.upper() in accepted:
                token = Token.new_borrow_pos(token.value.upper(), token.value, token)
            if token.type not in accepted:
                return False
        except Exception:  # never let recovery hide the real error
            return False
        recovered.append(_syntax_diagnostic(file, exc))
        parser_state.feed_token(Token("SEMICOLON", ";"))
        parser_state.feed_token(token)
        return True
    return on_error


class _FromTree(Transformer):
    """The fallback path: Lark's tree to nodes through the same `_ToNodes` callbacks. This class
    defines no rule-named methods, so Lark's public `__default__` hook gets every tree."""

    def __init__(self, nodes: _ToNodes) -> None:
        super().__init__(visit_tokens=False)
        self._nodes = nodes
        self._fns: dict[str, object] = {}

    def __default__(self, data, children, meta):
        fn = self._fns.get(data, 0)
        if fn == 0:
            fn = getattr(type(self._nodes), data, None)
            fn = self._fns[data] = fn if callable(fn) else None
        if fn is None:
            return Tree(data, children, meta)
        return fn(self._nodes, meta, children)


_INTS: list[int] = list(range(1024))


def _intern_lines(text: str) -> None:
    """Make `_INTS` cover every line number of `text` (plus one: a span may end after the last '\n')."""
    need = text.count("\n") + 2
    if len(_INTS) < need:
        _INTS.extend(range(len(_INTS), need))


@lru_cache(maxsize=None)
def _driver(start: str) -> lalr.Driver | None:
    """The fast driver over the parser's tables, or None (then Lark parses everything) if this
    Lark version's internals are not what the driver knows."""
    try:
        with collector_paused():   # (nested in a load's: left to it)
            return lalr.Driver(_parser(), start, _ToNodes)
    except lalr.Unsupported:
        return None


def _fast(text: str, file: str, settings: SysmacSettings, start: str):
    """(result, nodes, diagnostics) from the fast driver, or None when Lark must parse."""
    driver = _driver(start)
    if driver is None:
        return None
    _intern_lines(text)
    diagnostics: list[Diagnostic] = []
    nodes = _ToNodes(file, settings, diagnostics)
    try:
        with collector_paused():   # (nested in a load's: left to it)
            return driver.parse(text, nodes), nodes, diagnostics
    except Exception:   # lalr.Fallback, RecursionError, or anything unforeseen: Lark's path decides
        return None


def _unit(file: str, items: list, nodes: _ToNodes) -> n.CompilationUnit:
    out: dict[str, list] = {"types": [], "pous": [], "globals": [], "configurations": []}
    _collect(file, items, (), out)
    return n.CompilationUnit(file, tuple(out["types"]), tuple(out["pous"]), tuple(out["globals"]),
                             tuple(out["configurations"]), tuple(nodes.namespace_names),
                             frozenset(nodes.member_bases))


def parse_text(text: str, file: str, settings: SysmacSettings = DEFAULT_SETTINGS) -> tuple[n.CompilationUnit, list[Diagnostic]]:
    """Parse one ST file. On a syntax error the unit is empty and the error is a diagnostic."""
    if type(text) is not str and hasattr(text, "remap"):   # a vendor XML file (syntax/vendor_xml.py)
        return text.remap(*parse_text(str(text), file, settings))
    return _with_pragmas(_parse_fast_or_lark, text, file, settings)


def _parse_fast_or_lark(text: str, file: str, settings: SysmacSettings, pragma_tokens: list):
    fast = _fast(text, file, settings, "start")
    if fast is not None:
        items, nodes, diagnostics = fast
        return _unit(file, items, nodes), diagnostics
    del pragma_tokens[:]    # the fast driver gave up part-way: Lark lexes it all again
    return _parse_text_lark(text, file, settings)


def parse_text_lark(text: str, file: str, settings: SysmacSettings = DEFAULT_SETTINGS) -> tuple[n.CompilationUnit, list[Diagnostic]]:
    """`parse_text` by Lark's own parser and tree (the fallback path, and the reference the
    fast driver is tested against): syntax errors, recovery of missing ';', deep nesting."""
    return _with_pragmas(lambda text, file, settings, _: _parse_text_lark(text, file, settings), text, file, settings)


def _with_pragmas(parse, text: str, file: str, settings: SysmacSettings):
    """Run `parse` on the text with the branches of conditional compilation not taken blanked
    out (syntax/conditional.py), collecting the `{…}` pragmas the lexer drops (`_pragma_seen`,
    either parser), then attach the ones before a POU, type or global block to it (syntax/pragmas.py)."""
    directive_diagnostics: list[Diagnostic] = []
    if "{" in text:
        from stvm.syntax.conditional import preprocess   # lazy: start-up (only files with pragmas)
        text, directive_diagnostics = preprocess(text, file, settings.defines)
        if directive_diagnostics:   # the branches are not known: what the parser would say is noise
            return n.CompilationUnit(file, (), (), (), ()), directive_diagnostics
    _PRAGMAS.tokens = pragma_tokens = []
    try:
        unit, diagnostics = parse(text, file, settings, pragma_tokens)
    finally:
        _PRAGMAS.tokens = None
    if pragma_tokens:
        from stvm.syntax.pragmas import attach   # lazy: start-up (only files with pragmas)
        unit = attach(unit, pragma_tokens)
    return unit, diagnostics


def _parse_text_lark(text: str, file: str, settings: SysmacSettings) -> tuple[n.CompilationUnit, list[Diagnostic]]:
    diagnostics: list[Diagnostic] = []
    recovered: list[Diagnostic] = []
    try:
        tree = _parser().parse(text, start="start", on_error=_missing_semicolon_recovery(file, recovered))
    except UnexpectedInput as exc:
        diagnostics += recovered + [_syntax_diagnostic(file, exc)]
        return n.CompilationUnit(file, (), (), (), ()), diagnostics
    if recovered:
        return n.CompilationUnit(file, (), (), (), ()), recovered
    nodes = _ToNodes(file, settings, diagnostics)
    try:
        items = _FromTree(nodes).transform(tree)
    except RecursionError:
        diagnostics.append(Diagnostic.error(
            "expression or statement nesting too deep for stvm (split it into smaller parts)",
            n.Span(file, 1, 1, 1, 2), "E003"))
        return n.CompilationUnit(file, (), (), (), ()), diagnostics
    return _unit(file, items, nodes), diagnostics


def parse_expression(text: str, file: str = "<expr>", settings: SysmacSettings = DEFAULT_SETTINGS) -> tuple[n.Expr | None, list[Diagnostic]]:
    """Parse a lone ST expression (used by `--set`, the debugger's `print`, scenarios)."""
    fast = _fast(text, file, settings, "expression")
    if fast is not None:
        return fast[0], fast[2]
    return parse_expression_lark(text, file, settings)


def parse_expression_lark(text: str, file: str = "<expr>", settings: SysmacSettings = DEFAULT_SETTINGS) -> tuple[n.Expr | None, list[Diagnostic]]:
    """`parse_expression` by Lark's own parser (the fallback path and the reference)."""
    diagnostics: list[Diagnostic] = []
    try:
        tree = _parser().parse(text, start="expression")
    except UnexpectedInput as exc:
        return None, [_syntax_diagnostic(file, exc)]
    expr = _FromTree(_ToNodes(file, settings, diagnostics)).transform(tree)
    return expr, diagnostics


def parse_files(paths: Sequence[Path], settings: SysmacSettings = DEFAULT_SETTINGS) -> tuple[list[n.CompilationUnit], list[Diagnostic], dict[str, str]]:
    """Parse every file; returns units, diagnostics and the source texts (for excerpts)."""
    units: list[n.CompilationUnit] = []
    diagnostics: list[Diagnostic] = []
    sources: dict[str, str] = {}
    for path in paths:
        text = read_source(Path(path))
        name = str(path)
        sources[name] = text
        unit, diags = parse_text(text, name, settings)
        units.append(unit)
        diagnostics += diags
    return units, diagnostics, sources
