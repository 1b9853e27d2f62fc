"""A fast LALR(1) driver over Lark's own parse table and contextual lexer.

Lark's `parse()` builds a Tree (with a Meta per node and a Token per terminal), which
`parser._ToNodes` then walks. This driver runs the same automaton from Lark's tables and the
same per-state scanners (the regular expressions Lark compiled for each parser state), but
calls the node-building callbacks at reduction time, so no Tree, no Meta and no Token for
dropped keywords or punctuation is ever made.

It is generic over the grammar: for every rule it derives, from Lark's own rule options, what
Lark's tree builder would do (drop filtered tokens, insert `[ ]` placeholders, inline
`_rules`, expand `?rules` with one child, keep `!rules`' tokens) and how Lark would propagate
positions, so the callbacks receive the same children and the same spans.

Anything unusual — a syntax error, a character no scanner matches, nesting deep enough that
Lark's recursive transformer could fail, a grammar feature not handled here — raises
`Fallback`, and the caller runs Lark's own parser instead, so diagnostics are Lark's, byte for
byte. `tests/syntax/test_syntax_fast_parser.py` checks both paths give equal results.

Lark internals used (pinned in pyproject.toml; `check_lark_internals` fails loudly if they
change): `Lark.parser.parser.parser.parse_table` (an IntParseTable: `states`, `start_states`,
`end_states`, actions `(Shift, state)` / `(Reduce, rule)`), `Lark.parser.lexer` (a
ContextualLexer: `lexers` per state, each BasicLexer with `terminals`, `user_callbacks`, `re`,
`use_bytes`, `ignore_types`, `g_regex_flags`, `_scanner`), `lark.lexer._create_unless` (what
its `scanner` would hold, without compiling it), `lark.lexer.UnlessCallback.scanner`, and the rule
options (`expand1`, `keep_all_tokens`, `empty_indices`, `template_source`) and terminals'
`filter_out` and `pattern.to_regexp()`.

Scanning: each state's terminals are matched as Lark matches them (one alternation, Lark's
order, first alternative wins), with two changes that cannot change a result: the alternation
is split by the text's first character (`_ByFirstChar`: the terminals that cannot start with it,
worked out from the regex's parse by `_may_start_with`, are left out), and the whitespace
terminal's runs are matched as the tail of the token before them (`_skip_terminal`: only when
every scanner drops it and no terminal can start with one of its characters), so a token costs
one regex match instead of two.
"""

from __future__ import annotations

import functools
import re
import re._constants as _C
import re._parser as _sre_parse
from bisect import bisect_right
from itertools import accumulate
from operator import itemgetter
from types import FunctionType
from typing import Any

from lark import Lark, Token, Tree
from lark.lexer import CallChain, UnlessCallback, _create_unless
from lark.parsers.lalr_analysis import Reduce, Shift
from lark.tree import Meta

MAX_DEPTH = 150
"""Deeper parse trees go to Lark's parser: its transformer recurses twice per tree level, and
what happens near Python's recursion limit (the "nesting too deep" diagnostic) must stay Lark's."""


class Fallback(Exception):
    """This input needs Lark's own parser (a syntax error, or nesting too deep)."""


class Unsupported(Exception):
    """The grammar or the Lark version uses something this driver does not implement."""


class Inline:
    """An `_rule`'s children, spliced into its parent (Lark's ChildFilter)."""

    __slots__ = ("children", "spans")

    def __init__(self, children, spans):
        self.children = children
        self.spans = spans


class Meta2(tuple):
    """What a callback gets as `meta`: (start offset, end offset, line starts); start -1 for a
    rule that matched nothing. A tuple, so making one per reduction is cheap; it has the
    attributes of Lark's Meta too (line, column, end_line, end_column, empty, …)."""

    __slots__ = ()

    start = property(itemgetter(0))
    end = property(itemgetter(1))
    start_pos = start
    end_pos = end

    @property
    def empty(self):
        return self[0] < 0

    @property
    def line(self):
        return bisect_right(self[2], self[0])

    @property
    def column(self):
        lines = self[2]
        return self[0] - lines[bisect_right(lines, self[0]) - 1] + 1

    @property
    def end_line(self):
        return bisect_right(self[2], self[1])

    @property
    def end_column(self):
        lines = self[2]
        return self[1] - lines[bisect_right(lines, self[1]) - 1] + 1


class LazyToken(Token):
    """A kept terminal as the driver makes it: a Lark Token whose line and column are worked
    out from its offsets when asked (most tokens are only read as text: names, numbers,
    operators). `_lines` is the parse's line_starts list, shared by all its tokens."""

    __slots__ = ("_lines",)

    @property
    def line(self):
        return bisect_right(self._lines, self.start_pos)

    @property
    def column(self):
        lines = self._lines
        return self.start_pos - lines[bisect_right(lines, self.start_pos) - 1] + 1

    @property
    def end_line(self):
        return bisect_right(self._lines, self.end_pos)

    @property
    def end_column(self):
        lines = self._lines
        return self.end_pos - lines[bisect_right(lines, self.end_pos) - 1] + 1

    def eager(self) -> Token:
        """The same token as a plain Lark Token (what pickling and copying make of it)."""
        return Token(self.type, self.value, self.start_pos, self.line, self.column, self.end_line,
                     self.end_column, self.end_pos)

    def __reduce__(self):
        return self.eager().__reduce__()

    def __deepcopy__(self, memo):
        return self.eager()


def line_starts(text: str) -> list[int]:
    """Offsets where each line starts (index 0 is line 1)."""
    starts = [0]
    starts += accumulate(len(line) + 1 for line in text.split("\n"))
    return starts


def passes_child(fn):
    """Mark a one-child callback that returns its child unchanged (`return items[0]`): the
    driver then skips the call and its meta, keeping the tree depth it stands for."""
    fn.passes_child = True
    return fn


_PASS = object()   # a step of a one-child chain whose callback `passes_child`


# kinds of reduction plan (see Driver._plan)
_ONE, _APPEND, _GENERAL = 1, 2, 3

_new_str = str.__new__


def _lark_meta(meta: Meta2) -> Meta:
    out = Meta()
    if meta.start >= 0:
        out.empty = False
        out.line, out.column, out.start_pos = meta.line, meta.column, meta.start
        out.end_line, out.end_column, out.end_pos = meta.end_line, meta.end_column, meta.end
    return out


@functools.lru_cache(maxsize=4096)
def _parsed_regex(regex: str) -> tuple | None:
    """Python's own parse of a terminal's regex, or None; memoised: the same terminals stand in
    most of the ~170 per-state scanners, and parsing them again each time doubled the Driver's
    build (a cost every process that parses pays once)."""
    try:
        return tuple(_sre_parse.parse(regex))
    except Exception:
        return None


def _skip_chars(terminal) -> frozenset | None:
    """The characters of an ignored terminal of the form `[…]+` (a run of one class, as WS), or
    None. Such a run can be skipped as the tail of the token before it (see `_scanner`)."""
    parsed = _parsed_regex(terminal.pattern.to_regexp())
    if parsed is None:
        return None
    parsed = list(parsed)
    while len(parsed) == 1 and parsed[0][0] is _C.SUBPATTERN and not parsed[0][1][1] and not parsed[0][1][2]:
        parsed = list(parsed[0][1][3])
    if len(parsed) != 1 or parsed[0][0] is not _C.MAX_REPEAT:
        return None
    lo, hi, body = parsed[0][1]
    if lo != 1 or hi != _C.MAXREPEAT or len(body) != 1:
        return None
    op, arg = body[0]
    if op is _C.LITERAL:
        return frozenset(chr(arg))
    if op is _C.IN and all(o is _C.LITERAL for o, _a in arg):
        return frozenset(chr(a) for _o, a in arg)
    return None


def _may_start_with(items, chars: frozenset, ignorecase: bool = False) -> tuple[bool, bool]:
    """(could the parsed pattern's first character be one of `chars`, can it match empty): a
    superset answer (anything not understood here says yes)."""
    for op, arg in items:
        if op is _C.LITERAL:
            c = chr(arg)
            return (c in chars or (ignorecase and any(re.match(re.escape(c), x, re.IGNORECASE) for x in chars))), False
        if op is _C.NOT_LITERAL:
            return bool(chars - {chr(arg)}), False
        if op is _C.IN:
            if any(o is _C.NEGATE for o, _a in arg):
                return True, False
            for o, a in arg:
                if o is _C.LITERAL:
                    c = chr(a)
                    if c in chars or (ignorecase and any(re.match(re.escape(c), x, re.IGNORECASE) for x in chars)):
                        return True, False
                elif o is _C.RANGE:
                    if any(a[0] <= ord(c) <= a[1] for c in chars):
                        return True, False
                    if ignorecase:   # case folding as the regex engine does it: ask the engine
                        one = re.compile(f"[{re.escape(chr(a[0]))}-{re.escape(chr(a[1]))}]", re.IGNORECASE)
                        if any(one.match(c) for c in chars):
                            return True, False
                elif o is _C.CATEGORY:
                    if a not in (_C.CATEGORY_DIGIT, _C.CATEGORY_WORD) or any(c.isalnum() or c == "_" for c in chars):
                        return True, False
                else:
                    return True, False
            return False, False
        if op is _C.SUBPATTERN or op is _C.ATOMIC_GROUP:
            if op is _C.SUBPATTERN:
                _g, add, _del, sub = arg
                inner = ignorecase or bool(add & _C.SRE_FLAG_IGNORECASE)
            else:
                sub, inner = arg, ignorecase
            may, empty = _may_start_with(sub, chars, inner)
            if may or not empty:
                return may, False
            continue
        if op is _C.BRANCH:
            results = [_may_start_with(alt, chars, ignorecase) for alt in arg[1]]
            if any(may for may, _e in results):
                return True, False
            if not any(empty for _m, empty in results):
                return False, False
            continue
        if op in (_C.MAX_REPEAT, _C.MIN_REPEAT, _C.POSSESSIVE_REPEAT):
            lo, _hi, sub = arg
            may, empty = _may_start_with(sub, chars, ignorecase)
            if may:
                return True, False
            if lo and not empty:
                return False, False
            continue
        if op in (_C.AT, _C.ASSERT, _C.ASSERT_NOT):   # zero width: the next item decides
            continue
        return True, False
    return False, True


@functools.lru_cache(maxsize=4096)
def _regex_may_start_with(regex: str, chars: frozenset) -> bool:
    parsed = _parsed_regex(regex)
    return True if parsed is None else _may_start_with(list(parsed), chars)[0]


def _terminal_may_start_with(terminal, chars: frozenset) -> bool:
    return _regex_may_start_with(terminal.pattern.to_regexp(), chars)


_COMPILED: dict[tuple, Any] = {}   # ((name, regex) of each terminal, tail, flags) -> compiled match


def _compiled(terminals, tail: str, flags: int):
    """The match function of Lark's alternation of `terminals` (in that order) then `tail`."""
    key = (tuple((t.name, t.pattern.to_regexp()) for t in terminals), tail, flags)
    match = _COMPILED.get(key)
    if match is None:
        alternatives = "|".join(f"(?P<{t.name}>{t.pattern.to_regexp()})" for t in terminals)
        try:
            compiled = re.compile(f"(?:{alternatives}){tail}" if terminals else "(?!)", flags)
        except (re.error, AssertionError, OverflowError, RecursionError) as exc:
            raise Unsupported(f"a scanner regex does not compile: {exc!r}") from exc
        if any(compiled.groupindex.get(t.name) is None for t in terminals):
            raise Unsupported("a terminal is not a group of its scanner's regex")
        match = _COMPILED[key] = compiled.match
    return match


_IGNORED = object()   # a dropped terminal without a callback (see Driver._scanner)


def _lexer_parts(basic) -> tuple[list, dict]:
    """(terminals in Lark's order, callbacks) of one of Lark's BasicLexers, exactly as its
    `scanner` would hold them (`BasicLexer._build_scanner`), without building that scanner:
    Lark compiles each state's whole alternation there, ~40 % of the Driver's build, and this
    driver compiles its own (`_ByFirstChar`). A scanner Lark already built is read as it is."""
    if basic._scanner is not None:
        return basic._scanner.terminals, basic.callback
    terminals, callback = _create_unless(basic.terminals, basic.g_regex_flags, basic.re, basic.use_bytes)
    for type_, f in basic.user_callbacks.items():
        if type_ in callback:
            callback[type_] = CallChain(callback[type_], f, lambda t, type_=type_: t.type == type_)
        else:
            callback[type_] = f
    return terminals, callback


class _Retype(dict):
    """Text -> the keyword type Lark gives it (its UnlessCallback's scanner), or None; memoised."""

    __slots__ = ("fullmatch",)

    def __init__(self, fullmatch) -> None:
        super().__init__()
        self.fullmatch = fullmatch

    def __missing__(self, text: str):
        new = self[text] = self.fullmatch(text)
        return new


class _ByFirstChar(dict):
    """One scanner's match function per first character of the text to scan: Lark's alternation
    of that scanner's terminals, in Lark's order, without the terminals that cannot start with
    that character (the regex engine tries the alternatives one by one: most fail at the first
    character). Built on first use; a character beyond ASCII gets all the terminals."""

    def __init__(self, terminals, tail: str, flags: int) -> None:
        super().__init__()
        self.terminals = terminals
        self.tail = tail
        self.flags = flags

    @property
    def full(self):
        return _compiled(self.terminals, self.tail, self.flags)

    def __missing__(self, char: str):
        if ord(char) >= 128 or self.flags:   # (global flags would change how the regexes read)
            match = self.full
        else:
            match = _compiled(tuple(t for t in self.terminals if char in _first_chars(t)), self.tail, self.flags)
        self[char] = match
        return match


def _first_chars(terminal) -> frozenset:
    """The ASCII characters a match of `terminal` may start with."""
    return _regex_first_chars(terminal.pattern.to_regexp())


@functools.lru_cache(maxsize=4096)
def _regex_first_chars(regex: str) -> frozenset:
    parsed = _parsed_regex(regex)
    parsed = list(parsed) if parsed is not None else None
    return frozenset(chr(i) for i in range(128) if parsed is None or _may_start_with(parsed, frozenset(chr(i)))[0])


# ---- reductions as generated functions -----------------------------------------------------------
# Each rule's reduction is a small function made from its plan (Driver._plan) on its first use
# (_on_first_use): the child filter, the positions and the tree depth written out for that rule's
# shape, so a reduction runs only the steps its rule needs instead of testing every option of every
# rule (the plan interpreter this replaces was a third of the parse). Rules of one shape share one
# code object.

_PLAN_CODE: dict[str, Any] = {}   # source of a generated reduction -> its compiled code
_GENERATED_NAMES = {"Fallback": Fallback, "MAX_DEPTH": MAX_DEPTH, "Meta2": Meta2, "new_meta": tuple.__new__,
                    "Inline": Inline, "Tree": Tree, "_lark_meta": _lark_meta}


def _generated(source: str, constants: dict):
    """The function `plan` that `source` defines, its free names bound to `constants`."""
    code = _PLAN_CODE.get(source)
    if code is None:
        code = _PLAN_CODE[source] = compile(source, "<stvm.syntax.lalr reduction>", "exec")
    scope = dict(_GENERATED_NAMES, **constants)
    exec(code, scope)   # noqa: S102 (source made here from the grammar's rule shapes)
    return scope["plan"]


def _first_with_position(indices, nts) -> str:
    """`s_i or s_j or …`: the first span of the children at `indices` that has a position; a
    token always has one, so the chain stops at the first terminal."""
    out = []
    for i in indices:
        out.append(f"s{i}")
        if i not in nts:
            break
    return " or ".join(out)


def _children_source(pieces, tail: int, value: str, inlined: str, placeholder: str) -> str:
    """A list display of the kept children (`value` % i), the spliced children of inlined ones
    (`inlined` % i) and the placeholders of `[ ]` (Lark's ChildFilter)."""
    items = []
    for i, to_expand, add_none in pieces:
        items += [placeholder] * add_none
        items.append(("*" + inlined if to_expand else value) % i)
    items += [placeholder] * tail
    return "[" + ", ".join(items) + "]"


def _take_children(size: int, lines: list[str]) -> None:
    """Read the top `size` values and spans into v0… and s0…"""
    if size == 1:
        lines += ["    v0 = values[-1]", "    s0 = spans[-1]"]
    elif size:
        names = ", ".join(f"v{i}" for i in range(size))
        spans = ", ".join(f"s{i}" for i in range(size))
        lines += [f"    {names}, = values[-{size}:]", f"    {spans}, = spans[-{size}:]"]


def _push_source(size: int, value: str, span: str, lines: list[str]) -> None:
    """Replace the top `size` entries of the stacks by the reduction's (goto state, value, span)."""
    if size:
        lines.append(f"    state = goto[states[-{size + 1}]]")
        if size > 1:
            lines.append(f"    del states[-{size - 1}:], values[-{size - 1}:], spans[-{size - 1}:]")
        lines += ["    states[-1] = state", f"    values[-1] = {value}", f"    spans[-1] = {span}"]
    else:
        lines += ["    state = goto[states[-1]]", "    states.append(state)", f"    values.append({value})",
                  f"    spans.append({span})"]
    lines.append("    return state")


def _depth_source(nts, lines: list[str]) -> bool:
    """`d = ` the deepest child tree's depth (tokens have depth 0); False when it is always 0."""
    if not nts:
        lines.append("    d = 0")
        return False
    first, *others = nts
    lines.append(f"    d = s{first}[2] if s{first} else 0")
    for i in others:
        lines.append(f"    if s{i} and s{i}[2] > d: d = s{i}[2]")
    return True


def _positions_source(size: int, nts, lines: list[str]) -> bool:
    """`a`, `b`: the first and last child spans with a position (Lark's PropagatePositions), or
    falsy; True when some child is a token (then they always have one)."""
    if not size:
        lines.append("    a = b = None")
        return False
    lines.append(f"    a = {_first_with_position(range(size), nts)}")
    lines.append(f"    b = {_first_with_position(range(size - 1, -1, -1), nts)}")
    return len(nts) < size


def _general_plan(goto, size, name, simple, keep_idx, single, inline, tail, carry, fn, nts):
    """The reduction of a rule (`_GENERAL` plan) as a function of the parse stacks."""
    nts = frozenset(nts)
    pieces = [(i, False, 0) for i in (range(size) if keep_idx is None else keep_idx)] if simple else list(keep_idx)
    lines = ["def plan(states, values, spans, lines, handler):"]
    _take_children(size, lines)
    certain = _positions_source(size, nts, lines)
    deep = _depth_source(sorted(nts), lines)
    if len(pieces) == 1 and pieces[0][1] and not pieces[0][2] and not tail:
        lines.append(f"    children = v{pieces[0][0]}.children")       # one inlined rule's children as they are
    else:
        lines.append(f"    children = {_children_source(pieces, tail, 'v%d', 'v%d.children', 'None')}")
    expanded = any(to_expand for _i, to_expand, _n in pieces)
    ones = len(pieces) + tail + sum(n for _i, _e, n in pieces) == 1   # always one child
    if carry or (single and (expanded or ones)):
        lines.append(f"    cspans = {_children_source(pieces, tail, 's%d', 'v%d.spans', 'False')}")
    tree = []   # the rule's own node
    if deep:
        tree.append("if d >= MAX_DEPTH - 1: raise Fallback")
    call = "fn(handler, meta, children)" if fn is not None else "Tree(name, children, _lark_meta(meta))"
    if certain:
        tree += ["meta = new_meta(Meta2, (a[0], b[1], lines))", "span = (a[0], b[1], d + 1)"]
    else:
        tree += ["if a:", "    meta = new_meta(Meta2, (a[0], b[1], lines))", "    span = (a[0], b[1], d + 1)",
                 "else:", "    meta = new_meta(Meta2, (-1, -1, lines))", "    span = None"]
    tree.append(f"value = {call}")
    if inline:
        tree = [f"value = Inline(children, {'cspans' if carry else 'None'})",
                "span = (a[0], b[1], d)" + ("" if certain else " if a else None")]
    # a ?rule with one child returns it; positions as Lark propagates them
    one = ["value = children[0]", "csp = cspans[0]", "if csp is False or csp is None:",
           "    if csp is None and a: raise Fallback   # Lark would give the empty child tree a position here",
           "    span = csp", "elif csp[2] == 0:", "    span = csp       # a token keeps its own position",
           "else:", "    span = (a[0], b[1], csp[2])"]
    if single and expanded:
        lines.append("    if len(children) == 1:")
        lines += ["        " + line for line in one]
        lines.append("    else:")
        lines += ["        " + line for line in tree]
    else:
        lines += ["    " + line for line in (one if single and ones else tree)]
    _push_source(size, "value", "span", lines)
    return _generated("\n".join(lines) + "\n", {"goto": goto, "fn": fn, "name": name})


def _append_plan(goto, rest, size, carry, nts):
    """The reduction of an `_rule` that adds children to the inlined list it starts with (`_APPEND`)."""
    nts = frozenset(nts)
    lines = ["def plan(states, values, spans, lines, handler):"]
    _take_children(size, lines)
    lines.append("    children = v0.children")
    lines += [f"    children.append(v{i})" for i in rest]
    if carry:
        lines.append("    cspans = v0.spans")
        lines += [f"    cspans.append(s{i})" for i in rest]
    certain = _positions_source(size, nts, lines)
    _depth_source(sorted(nts), lines)
    _push_source(size, "v0", "(a[0], b[1], d)" + ("" if certain else " if a else None"), lines)
    return _generated("\n".join(lines) + "\n", {"goto": goto})


def _chain_plan(steps):
    """A run of one-child reductions ([(callback or _PASS, rule name)]) as a function of the top
    of the stacks, or None when it changes nothing but the state."""
    if not steps:
        return None
    k = len(steps)
    calls = []
    constants = {}
    for j, (fn, name) in enumerate(steps):
        if fn is _PASS:
            continue
        constants[f"fn{j}"], constants[f"name{j}"] = fn, name
        calls.append(f"v = fn{j}(handler, meta, [v])" if fn is not None else
                     f"v = Tree(name{j}, [v], _lark_meta(meta))")
    lines = ["def plan(states, values, spans, lines, handler):", "    sp = spans[-1]", "    if sp:",
             f"        d = sp[2] + {k}", "        if d >= MAX_DEPTH: raise Fallback"]
    if calls:
        lines += ["        meta = new_meta(Meta2, (sp[0], sp[1], lines))", "        v = values[-1]"]
        lines += ["        " + c for c in calls]
        lines.append("        values[-1] = v")
    lines.append("        spans[-1] = (sp[0], sp[1], d)")
    if calls:
        lines += ["    else:", "        meta = new_meta(Meta2, (-1, -1, lines))", "        v = values[-1]"]
        lines += ["        " + c for c in calls]
        lines.append("        values[-1] = v")
    return _generated("\n".join(lines) + "\n", constants)


def _on_first_use(plan: tuple, rows: list):
    """A stand-in for the function of a `_GENERAL` or `_APPEND` plan: makes it, puts it in
    its place in the action `rows` it stands in and runs it."""
    def first_use(states, values, spans, lines, handler):
        fn = _general_plan(*plan[1:]) if plan[0] == _GENERAL else _append_plan(*plan[1:])
        for row in rows:
            for sym, act in row.items():
                if act is first_use:
                    row[sym] = fn
        return fn(states, values, spans, lines, handler)
    return first_use


class _OneChildRun(dict):
    """The action of a one-child reduction (`plan`: a `?rule` pass-through's goto dict or an
    `_ONE` plan) in `state` on lookahead `ttype`: a run of such reductions only changes the top
    of the stack, and its course depends on the state below it, so this maps that state to the
    run's (final state, function or None) (Driver._chain), worked out on first use."""

    __slots__ = ("driver", "state", "ttype", "plan")

    def __init__(self, driver, state: int, ttype: str, plan) -> None:
        super().__init__()
        self.driver, self.state, self.ttype, self.plan = driver, state, ttype, plan

    def __missing__(self, below: int) -> tuple:
        run = self[below] = self.driver._chain(below, self.state, self.ttype)
        return run


class Driver:
    """Built once per Lark object, start symbol and callback class; `parse(text, handler)`
    runs it. `handler_type` has one function per rule name (or alias) taking
    (handler, meta, children); a rule without one becomes a lark Tree, as Lark would build."""

    def __init__(self, lark: Lark, start: str, handler_type: type) -> None:
        try:
            frontend = lark.parser
            table = frontend.parser.parser.parse_table
            contextual = frontend.lexer
            states = table.states
            self.start_state = table.start_states[start]
            self.end_state = table.end_states[start]
            options = lark.options
        except (AttributeError, KeyError) as exc:
            raise Unsupported(f"Lark's parser internals changed: {exc!r}") from exc
        if options.lexer != "contextual" or options.parser != "lalr":
            raise Unsupported("needs parser='lalr', lexer='contextual'")
        if options.propagate_positions is not True:
            raise Unsupported("needs propagate_positions=True")
        if options.postlex is not None:
            raise Unsupported("postlex is not supported")
        user_callbacks = dict(options.lexer_callbacks or {})
        if options.tree_class not in (None, Tree) or options.transformer is not None:
            raise Unsupported("a custom tree_class or an inline transformer is not supported")
        self.maybe_placeholders = bool(options.maybe_placeholders)
        n_states = len(states)
        if set(states) != set(range(n_states)):
            raise Unsupported("parse table states are not 0..n-1")

        rules: dict[int, Any] = {}
        for acts in states.values():
            for action, arg in acts.values():
                if action is Reduce:
                    rules.setdefault(id(arg), arg)
                elif action is not Shift:
                    raise Unsupported(f"unknown parse action {action!r}")
        rule_list = list(rules.values())
        gotos: dict[str, dict[int, int]] = {}
        for s in range(n_states):
            for sym, (action, arg) in states[s].items():
                if action is Shift and not (sym.isupper() or sym == "$END"):
                    gotos.setdefault(sym, {})[s] = arg

        inline_min = self._min_inline_children(rule_list)
        carry = self._inlines_needing_spans(rule_list, inline_min)
        self.kept_terminals: set[str] = set()
        plans = {id(r): self._plan(r, gotos.get(r.origin.name, {}), inline_min, carry, handler_type)
                 for r in rule_list}
        # the reductions of more than one child: functions made on first use (making all of
        # them here doubled the Driver's build, and a parse meets a fraction of the rules)
        uses: dict[int, list] = {}   # plan id -> the rows it stands in
        stand_ins = {key: _on_first_use(plan, uses.setdefault(key, [])) for key, plan in plans.items()
                     if plan.__class__ is tuple and plan[0] in (_GENERAL, _APPEND)}
        # one row per state: terminal -> shift target (int), a reduction (function) or a run of
        # one-child reductions (_OneChildRun)
        self.actions = []
        for s in range(n_states):
            row = {}
            for sym, (action, arg) in states[s].items():
                if action is Shift:
                    if sym.isupper() and sym != "$END":   # Lark never shifts $END: no entry, Fallback
                        row[sym] = arg
                elif id(arg) in stand_ins:
                    row[sym] = stand_ins[id(arg)]
                    rows = uses[id(arg)]
                    if not rows or rows[-1] is not row:
                        rows.append(row)
                else:
                    row[sym] = _OneChildRun(self, s, sym, plans[id(arg)])
            self.actions.append(row)

        # per-state scanners: Lark's BasicLexer for that state
        if options.use_bytes or options.regex:
            raise Unsupported("use_bytes and the regex module are not supported")
        try:
            lexers = contextual.lexers
            # one entry per distinct BasicLexer (Lark shares one among the states that accept the
            # same terminals: ~190 for ~870 states); `_lexer_parts` runs Lark's `_create_unless`,
            # which matches every string terminal against every regex terminal, once for each
            parts: dict[int, tuple] = {}
            for s in range(n_states):
                basic = lexers[s]
                if id(basic) not in parts:
                    parts[id(basic)] = (basic, _lexer_parts(basic))
            skip = self._skip_terminal([(basic, terms) for basic, (terms, _c) in parts.values()], user_callbacks)
            scanners = []
            by_lexer: dict[int, tuple] = {}
            for s in range(n_states):
                basic = lexers[s]
                entry = by_lexer.get(id(basic))
                if entry is None:
                    entry = by_lexer[id(basic)] = self._scanner(basic, *parts[id(basic)][1], skip, user_callbacks)
                scanners.append(entry)
        except AttributeError as exc:
            raise Unsupported(f"Lark's lexer internals changed: {exc!r}") from exc
        # a skip run at the start of the text (later ones are matched as the tail of a token)
        self.skip_leading = re.compile(f"(?:{skip.pattern.to_regexp()})?+").match if skip is not None else None
        self.scanners = scanners

    @staticmethod
    def _skip_terminal(lexers, user_callbacks):
        """The ignored `[…]+` terminal (WS) that every scanner drops and no other terminal of any
        scanner can start like: its runs can then be matched as the tail of the token before
        them, one regex match per token instead of two. None if there is none such. `lexers`:
        (BasicLexer, its terminals as `_lexer_parts` gives them) per distinct lexer."""
        if any(basic.g_regex_flags for basic, _t in lexers):   # they would change how the regexes read
            return None
        terminal_lists = [terminals for _b, terminals in lexers]
        candidates = None
        for basic, terminals in lexers:
            names = {t.name: t for t in terminals}
            here = {name for name in basic.ignore_types if name in names and name not in user_callbacks
                    and _skip_chars(names[name]) is not None}
            candidates = here if candidates is None else candidates & here
        for name in sorted(candidates or ()):
            terminal = next(t for t in terminal_lists[0] if t.name == name)
            chars = _skip_chars(terminal)
            if all(_skip_chars(t) == chars for ts in terminal_lists for t in ts if t.name == name) and \
                    not any(t.name != name and _terminal_may_start_with(t, chars)
                            for ts in terminal_lists for t in ts):
                return terminal
        return None

    @staticmethod
    def _scanner(basic, lark_terminals, callbacks, skip, user_callbacks):
        """(match, special) for one of Lark's per-state lexers. `match[first character]` is one regex,
        Lark's alternatives in Lark's order (the skip terminal left out, its runs matched after
        the token, possessively: `m.end(m.lastindex)` is the token's end, `m.end()` the next one's
        start)."""
        terminals = tuple(t for t in lark_terminals if skip is None or t.name != skip.name)
        # `special[type]`: None for most terminals; _IGNORED for a dropped one; the user callback
        # of a dropped one that has one (the pragmas: seen, then dropped); a _Retype for one that
        # Lark retypes when its text is a keyword's (an UnlessCallback)
        special = {t.name: None for t in terminals}
        for type_, cb in callbacks.items():
            if type_ in user_callbacks and type_ in basic.ignore_types:
                special[type_] = user_callbacks[type_]
                continue
            if not isinstance(cb, UnlessCallback) or not callable(getattr(cb.scanner, "fullmatch", None)):
                raise Unsupported(f"lexer callback for {type_} is not an UnlessCallback with fullmatch")
            if type_ not in basic.ignore_types:
                special[type_] = _Retype(cb.scanner.fullmatch)
        for type_ in basic.ignore_types:
            if special.get(type_, 0) is None:
                special[type_] = _IGNORED
        tail = f"(?:{skip.pattern.to_regexp()})?+" if skip is not None else ""
        # the regexes compile on first use (per first character): compiling every state's whole
        # alternation here cost a third of the Driver's build; one that fails to compile
        # mid-parse raises Unsupported there, and that text goes to Lark's parser (parser.py)
        return (_ByFirstChar(terminals, tail, basic.g_regex_flags), special)

    def _chain(self, below: int, state: int, ttype: str) -> tuple:
        """(final state, its reductions as a function or None) of the run of one-child reductions
        in `state` on lookahead `ttype` with `below` the state under it."""
        steps = []
        while True:
            act = self.actions[state].get(ttype)
            if act.__class__ is _OneChildRun:
                act = act.plan
            else:
                break
            if act.__class__ is dict:
                nxt = act.get(below)
            elif act.__class__ is tuple and act[0] == _ONE:
                nxt = act[1].get(below)
                fn = act[2]
                steps.append((_PASS if getattr(fn, "passes_child", False) else fn, act[3]))
            else:
                break
            if nxt is None:
                raise Fallback
            state = nxt
            if state == self.end_state:
                break
        return state, _chain_plan(steps)

    # ---- build time --------------------------------------------------------------------------

    def _keep(self, rule):
        """Lark's maybe_create_child_filter: [(raw index, inline it, Nones before it)], Nones after."""
        expansion = rule.expansion
        keep_all = rule.options.keep_all_tokens
        empty = rule.options.empty_indices if self.maybe_placeholders else None
        if empty:
            s = "".join(str(int(b)) for b in empty)
            nones = [len(ones) for ones in s.split("0")]
        else:
            nones = [0] * (len(expansion) + 1)
        out = []
        pending = 0
        for i, sym in enumerate(expansion):
            pending += nones[i]
            if keep_all or not (sym.is_term and sym.filter_out):
                out.append((i, (not sym.is_term) and sym.name.startswith("_"), pending))
                pending = 0
        pending += nones[len(expansion)]
        return out, pending

    def _min_inline_children(self, rules) -> dict[str, float]:
        """Fewest children each `_rule` can splice into its parent (for the `?rule` analysis)."""
        inf = float("inf")
        best: dict[str, float] = {r.origin.name: inf for r in rules if r.origin.name.startswith("_")}
        changed = True
        while changed:
            changed = False
            for r in rules:
                name = r.origin.name
                if name not in best:
                    continue
                keep, tail = self._keep(r)
                count = tail + sum(nb + (best.get(r.expansion[i].name, inf) if inl else 1) for i, inl, nb in keep)
                if count < best[name]:
                    best[name] = count
                    changed = True
        return best

    def _fewest_children(self, rule, inline_min) -> float:
        """Fewest children a rule's callback can get (its `_rule` children spliced in)."""
        keep, tail = self._keep(rule)
        return tail + sum(nb + (inline_min.get(rule.expansion[i].name, 0) if inl else 1) for i, inl, nb in keep)

    def _inlines_needing_spans(self, rules, inline_min) -> set[str]:
        """`_rules` whose children may become a `?rule`'s only child, which then needs each
        child's position (token, tree or None). A `?rule` that always has more than one child
        (`expression`: an operand, then operators and operands) never needs them."""
        need: set[str] = set()
        may_be_single = {id(r) for r in rules if r.options.expand1 and not r.alias
                         and self._fewest_children(r, inline_min) <= 1}
        changed = True
        while changed:
            changed = False
            for r in rules:
                if r.origin.name not in need and id(r) not in may_be_single:
                    continue
                for i, inl, _nb in self._keep(r)[0]:
                    name = r.expansion[i].name
                    if inl and name not in need:
                        need.add(name)
                        changed = True
        return need

    def _plan(self, rule, goto: dict[int, int], inline_min, carry_set, handler_type):
        expansion = rule.expansion
        size = len(expansion)
        name = rule.alias or rule.options.template_source or rule.origin.name
        expand1 = bool(rule.options.expand1 and not rule.alias)
        inline = rule.origin.name.startswith("_")
        if inline and expand1:
            raise Unsupported(f"inlined rule {rule.origin.name} with '?' is not supported")
        carry = inline and rule.origin.name in carry_set
        keep, tail = self._keep(rule)
        for i, _inl, _nb in keep:
            if expansion[i].is_term:
                self.kept_terminals.add(expansion[i].name)
        fn = None if inline else getattr(handler_type, name, None)
        if not callable(fn):
            fn = None
        if expand1 and size == 1 and keep == [(0, False, 0)] and not tail:
            return goto                                   # a `?rule` passing its one child on
        if not expand1 and not inline and size == 1 and keep == [(0, False, 0)] and not tail:
            return (_ONE, goto, fn, name)
        rest = keep[1:]
        nts = tuple(i for i, sym in enumerate(expansion) if not sym.is_term)   # tokens have depth 0
        if (inline and not tail and keep and keep[0] == (0, True, 0)
                and all(not inl and not nb for _i, inl, nb in rest)):
            return (_APPEND, goto, tuple(i for i, _inl, _nb in rest), size, carry, nts)
        simple = all(not inl and not nb for _i, inl, nb in keep) and not tail
        if simple:
            idx = tuple(i for i, _inl, _nb in keep)
            keep_idx = None if idx == tuple(range(size)) else idx
        else:
            keep_idx = tuple(keep)
        # can this ?rule end up with a single child (then the child's position kind matters)?
        single = expand1 and self._fewest_children(rule, inline_min) <= 1
        return (_GENERAL, goto, size, name, simple, keep_idx, single, inline, tail, carry, fn, nts)

    # ---- run time ----------------------------------------------------------------------------

    def parse(self, text: str, handler) -> Any:
        """The start rule's callback result; raises Fallback when Lark must parse this text."""
        lines = line_starts(text)
        actions = self.actions
        scanners = self.scanners
        kept = self.kept_terminals
        end_state = self.end_state
        n = len(text)
        states = [self.start_state]
        values: list = []
        spans: list = []
        pos = 0
        new_str = _new_str
        token_cls = Token
        lazy_cls = LazyToken
        bisect = bisect_right
        int_ = int
        function_ = FunctionType
        retype_cls = _Retype
        ignored = _IGNORED
        m = None
        end = 0
        if self.skip_leading is not None:
            pos = self.skip_leading(text, 0).end()
        state = self.start_state
        while True:
            # ---- next token, with the scanner of the current state
            match, special = scanners[state]
            while True:
                if pos >= n:
                    ttype = "$END"
                    break
                m = match[text[pos]](text, pos)
                if m is None:
                    raise Fallback
                ttype = m.lastgroup
                end = m.end(m.lastindex)
                how = special[ttype]
                if how is None:                  # most tokens
                    break
                if how.__class__ is retype_cls:  # a keyword-shaped name becomes the keyword
                    new = how[text[pos:end]]
                    if new is not None:
                        ttype = new
                    break
                if how is not ignored:           # what Lark's lexer does for an ignored token with a callback
                    line = bisect(lines, pos)
                    how(token_cls(ttype, text[pos:end], pos, line, pos - lines[line - 1] + 1))
                pos = m.end()
            # ---- reduce while the table says so, then shift
            while True:
                try:
                    act = actions[state][ttype]
                except KeyError:   # no action: a syntax error (Lark reports it)
                    raise Fallback from None
                cls = act.__class__
                if cls is int_:                                         # shift
                    states.append(act)
                    state = act
                    if ttype in kept:
                        value = text[pos:end]
                        tok = new_str(lazy_cls, value)
                        tok.type = ttype
                        tok.value = value
                        tok.start_pos = pos
                        tok.end_pos = end
                        tok._lines = lines
                        values.append(tok)
                    else:
                        values.append(None)
                    spans.append((pos, end, 0))
                    pos = m.end()
                    break
                if cls is function_:                                    # reduce
                    state = act(states, values, spans, lines, handler)
                    if state == end_state:
                        if ttype != "$END":
                            # the start rules share states: `1;` reduces to a whole expression on
                            # `;`, with text left over; only the end of the input ends the parse
                            # (issue 34 item 10: `--set Main.x=1; DROP` was taken as 1)
                            raise Fallback
                        return values[-1]
                    continue
                # a run of one-child reductions (an _OneChildRun): worked out once per state below
                final, run = act[states[-2]]
                if run is not None:
                    run(states, values, spans, lines, handler)
                states[-1] = state = final
                if state == end_state:
                    if ttype != "$END":   # (as above)
                        raise Fallback
                    return values[-1]


def check_lark_internals(lark: Lark, handler_type: type = object) -> list[str]:
    """What of Lark's internals this driver needs is missing (empty when all is there)."""
    problems = []
    for start in lark.options.start:
        try:
            Driver(lark, start, handler_type)
        except Unsupported as exc:
            problems.append(f"{start}: {exc}")
    return problems
