"""The TM script subset: tokenizer, parser and static checks (spec §4.1, §7).

A TMSCT script is one statement per CRLF-separated line.  :func:`parse_script` returns the parsed
lines plus the 1-based numbers of lines with errors; the robot answers ``ERROR;<lines>`` for those
and executes nothing of the script (spec §4.2).  Errors found here: syntax, bare CR/LF, unknown
function, wrong argument count or types, undeclared or re-declared variable, non-literal priority
argument.  Argument *values* (format strings, ranges, reachability) are checked by the robot when
it dry-runs the script (``robot.py``), by the built-ins in ``builtins.py``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Iterable, Union

# ----------------------------------------------------------------------------- AST


@dataclass(frozen=True)
class Num:
    value: float | int


@dataclass(frozen=True)
class Str:
    value: str


@dataclass(frozen=True)
class Bool:
    value: bool


@dataclass(frozen=True)
class ArrayLit:
    items: tuple["Expr", ...]


@dataclass(frozen=True)
class Name:
    name: str


@dataclass(frozen=True)
class Index:
    target: "Expr"
    index: "Expr"


@dataclass(frozen=True)
class Attr:
    target: "Expr"
    name: str


@dataclass(frozen=True)
class Call:
    name: str
    args: tuple["Expr", ...]


@dataclass(frozen=True)
class Unary:
    op: str
    operand: "Expr"


@dataclass(frozen=True)
class Binary:
    op: str
    left: "Expr"
    right: "Expr"


@dataclass(frozen=True)
class Postfix:
    op: str  # "++" / "--"
    target: "Expr"


Expr = Union[Num, Str, Bool, ArrayLit, Name, Index, Attr, Call, Unary, Binary, Postfix]


@dataclass(frozen=True)
class Declare:
    type_name: str  # lower-case: int, float, double, string, bool, byte
    is_array: bool
    name: str
    init: Expr | None


@dataclass(frozen=True)
class Assign:
    target: Expr
    op: str  # "=", "+=", ...
    value: Expr


@dataclass(frozen=True)
class ExprStmt:
    expr: Expr


@dataclass(frozen=True)
class Empty:
    pass


Statement = Union[Declare, Assign, ExprStmt, Empty]


@dataclass(frozen=True)
class Line:
    number: int  # 1-based, as in ERROR;<line> (spec §4.2)
    statement: Statement


@dataclass(frozen=True)
class ParsedScript:
    lines: tuple[Line, ...]
    error_lines: tuple[int, ...]
    declared: tuple[str, ...] = ()  # names this script declares (lower-case)
    priority: "PriorityCommand | None" = None


@dataclass(frozen=True)
class PriorityCommand:
    """``ScriptExit(0|1)`` or ``StopAndClearBuffer(0|1|2)`` with a literal argument (spec §4.5)."""

    name: str  # "ScriptExit" / "StopAndClearBuffer"
    mode: int
    line: int


class ScriptSyntaxError(Exception):
    pass


# ----------------------------------------------------------------------------- tokens

TYPE_NAMES = {"int", "float", "double", "string", "bool", "byte"}

_TOKEN_RE = re.compile(
    r"""
    (?P<ws>[ \t]+)
  | (?P<comment>//.*)
  | (?P<num>(?:0[xX][0-9A-Fa-f]+|0[bB][01]+|(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?))
  | (?P<str>"(?:[^"\\]|\\.)*")
  | (?P<name>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<op>\+\+|--|\+=|-=|\*=|/=|==|!=|<=|>=|&&|\|\||[-+*/%<>=!(){}\[\],.])
    """,
    re.VERBOSE,
)


@dataclass(frozen=True)
class Token:
    kind: str
    text: str


def tokenize(line: str) -> list[Token]:
    tokens: list[Token] = []
    pos = 0
    while pos < len(line):
        match = _TOKEN_RE.match(line, pos)
        if match is None:
            # Typographic quotes, stray "$", "*" alone is an op... anything else: syntax error.
            raise ScriptSyntaxError(f"unexpected {line[pos]!r}")
        kind = match.lastgroup or ""
        if kind not in ("ws", "comment"):
            tokens.append(Token(kind, match.group()))
        pos = match.end()
    return tokens


# ----------------------------------------------------------------------------- parser

_BINARY_PRECEDENCE = [
    ("||",), ("&&",), ("==", "!="), ("<", ">", "<=", ">="), ("+", "-"), ("*", "/", "%"),
]


# How deep one line may nest. The descent counts brackets, calls, array literals and unary
# operators; the finished tree is measured too, since a chain (`1+1+…`, `a[0][0]…`) is parsed in a
# loop but builds a tree as deep as it is long, which the checker and the evaluator then recurse
# through. TM scripts written by people or by the thesis library stay below 10 levels; the limits
# keep a hostile frame from exhausting Python's recursion (the line is refused as a syntax error,
# ERROR;<line>, as any other malformed line is).
MAX_NESTING = 64
MAX_TREE_DEPTH = 160
# The longest number literal taken: ~300 digits cover every float and integer a TM variable can
# hold; Python refuses to convert over 4,300 digits (a ValueError, not a syntax error).
MAX_NUMBER_CHARS = 400


class _Parser:
    def __init__(self, tokens: list[Token]) -> None:
        self.tokens = tokens
        self.pos = 0
        self.depth = 0   # the recursion depth of the descent now (see MAX_NESTING)

    def nest(self) -> None:
        self.depth += 1
        if self.depth > MAX_NESTING:
            raise ScriptSyntaxError(f"expression nested deeper than {MAX_NESTING} levels")

    def peek(self, offset: int = 0) -> Token | None:
        i = self.pos + offset
        return self.tokens[i] if i < len(self.tokens) else None

    def take(self, text: str | None = None) -> Token:
        tok = self.peek()
        if tok is None or (text is not None and tok.text != text):
            raise ScriptSyntaxError(f"expected {text or 'token'}")
        self.pos += 1
        return tok

    def at(self, text: str) -> bool:
        tok = self.peek()
        return tok is not None and tok.text == text and tok.kind in ("op",)

    def statement(self) -> Statement:
        if not self.tokens:
            return Empty()
        first = self.peek()
        assert first is not None
        if first.kind == "name" and first.text.lower() in TYPE_NAMES:
            return self.declaration()
        expr = self.expression()
        nxt = self.peek()
        if nxt is not None and nxt.kind == "op" and nxt.text in ("=", "+=", "-=", "*=", "/="):
            self.pos += 1
            if not isinstance(expr, (Name, Index, Attr)):
                raise ScriptSyntaxError("cannot assign to this")
            value = self.expression()
            self.end()
            return Assign(expr, nxt.text, value)
        self.end()
        return ExprStmt(expr)

    def declaration(self) -> Declare:
        type_name = self.take().text.lower()
        is_array = False
        if self.at("["):
            self.take("[")
            self.take("]")
            is_array = True
        tok = self.take()
        if tok.kind != "name" or tok.text.lower() in TYPE_NAMES or tok.text.lower() in ("true", "false"):
            raise ScriptSyntaxError("expected a variable name")
        init = None
        if self.at("="):
            self.take("=")
            init = self.expression()
        self.end()
        return Declare(type_name, is_array, tok.text, init)

    def end(self) -> None:
        if self.peek() is not None:
            raise ScriptSyntaxError(f"unexpected {self.peek().text!r}")  # type: ignore[union-attr]

    def expression(self, level: int = 0) -> Expr:
        if level == 0:
            self.nest()
            try:
                return self._binary(0)
            finally:
                self.depth -= 1
        return self._binary(level)

    def _binary(self, level: int) -> Expr:
        if level == len(_BINARY_PRECEDENCE):
            return self.unary()
        left = self._binary(level + 1)
        while True:
            tok = self.peek()
            if tok is None or tok.kind != "op" or tok.text not in _BINARY_PRECEDENCE[level]:
                return left
            self.pos += 1
            left = Binary(tok.text, left, self._binary(level + 1))

    def unary(self) -> Expr:
        tok = self.peek()
        if tok is not None and tok.kind == "op" and tok.text in ("-", "+", "!"):
            self.pos += 1
            self.nest()
            try:
                return Unary(tok.text, self.unary())
            finally:
                self.depth -= 1
        return self.postfix()

    def postfix(self) -> Expr:
        expr = self.primary()
        while True:
            tok = self.peek()
            if tok is None or tok.kind != "op":
                return expr
            if tok.text == "[":
                self.pos += 1
                index = self.expression()
                self.take("]")
                expr = Index(expr, index)
            elif tok.text == ".":
                self.pos += 1
                name = self.take()
                if name.kind != "name":
                    raise ScriptSyntaxError("expected a member name")
                expr = Attr(expr, name.text)
            elif tok.text in ("++", "--"):
                self.pos += 1
                if not isinstance(expr, (Name, Index)):
                    raise ScriptSyntaxError(f"{tok.text} needs a variable")
                expr = Postfix(tok.text, expr)
            else:
                return expr

    def primary(self) -> Expr:
        tok = self.take()
        if tok.kind == "num":
            return Num(parse_number(tok.text))
        if tok.kind == "str":
            return Str(_unescape(tok.text[1:-1]))
        if tok.kind == "name":
            lower = tok.text.lower()
            if lower in ("true", "false"):  # §7: booleans are case-insensitive
                return Bool(lower == "true")
            if self.at("("):
                self.take("(")
                args: list[Expr] = []
                if not self.at(")"):
                    args.append(self.expression())
                    while self.at(","):
                        self.take(",")
                        args.append(self.expression())
                self.take(")")
                return Call(tok.text, tuple(args))
            return Name(tok.text)
        if tok.text == "(":
            inner = self.expression()
            self.take(")")
            return inner
        if tok.text == "{":
            items: list[Expr] = []
            if not self.at("}"):
                items.append(self.expression())
                while self.at(","):
                    self.take(",")
                    items.append(self.expression())
            self.take("}")
            return ArrayLit(tuple(items))
        raise ScriptSyntaxError(f"unexpected {tok.text!r}")


def parse_number(text: str) -> int | float:
    """Numbers per spec §7: ``123``, ``34.567``, ``3.4e5``, ``0x1F``, ``0b101``."""
    if len(text) > MAX_NUMBER_CHARS:
        raise ScriptSyntaxError(f"number literal longer than {MAX_NUMBER_CHARS} characters")
    low = text.lower()
    if low.startswith("0x"):
        return int(low[2:], 16)
    if low.startswith("0b"):
        return int(low[2:], 2)
    if any(c in low for c in ".e"):
        return float(low)
    return int(low, 10)


def _unescape(body: str) -> str:
    return re.sub(r"\\(.)", lambda m: {"n": "\n", "r": "\r", "t": "\t"}.get(m.group(1), m.group(1)), body)


def parse_statement(line: str) -> Statement:
    stmt = _Parser(tokenize(line)).statement()
    if tree_depth(stmt) > MAX_TREE_DEPTH:
        raise ScriptSyntaxError(f"expression nested deeper than {MAX_TREE_DEPTH} levels")
    return stmt


def tree_depth(node: object) -> int:
    """How deep the tree under `node` is (walked with a stack, never recursively)."""
    deepest = 0
    stack = [(node, 1)]
    while stack:
        item, depth = stack.pop()
        deepest = max(deepest, depth)
        for name in getattr(item, "__dataclass_fields__", ()):
            child = getattr(item, name)
            if isinstance(child, tuple):
                stack.extend((c, depth + 1) for c in child)
            elif hasattr(child, "__dataclass_fields__"):
                stack.append((child, depth + 1))
    return deepest


# ----------------------------------------------------------------------------- functions

# Argument kinds for static checking.  "N" number, "S" string, "B" bool, "A" array,
# "X" anything.  A number is accepted where a bool is expected? No: TM's bool parameters are
# written true/false by every client (§7), so "B" takes a bool expression only.
ARR6_FLAT = ("N",) * 6


def _motion_forms(flat_tail: tuple[str, ...], *extra_forms: tuple[str, ...]) -> tuple[tuple[str, ...], ...]:
    return (("S", "A") + flat_tail, ("S",) + ARR6_FLAT + flat_tail) + extra_forms


@dataclass(frozen=True)
class FunctionSpec:
    """A script function: the argument kinds of each accepted form (spec §7 table) and its class.

    ``kind``: ``queued`` appends to the motion queue; ``instant`` runs when the line runs;
    ``blocking`` may hold the script (its reply waits, spec §4.3)."""

    name: str
    forms: tuple[tuple[str, ...], ...]
    kind: str
    returns: str = "B"


FUNCTIONS: dict[str, FunctionSpec] = {
    spec.name.lower(): spec
    for spec in (
        # PTP: 6 (array), 7 (array + int[3] pose), 11 (flat), 14 (flat + 3 pose ints) [§7].
        FunctionSpec("PTP", _motion_forms(("N", "N", "N", "B"),
                                          ("S", "A", "N", "N", "N", "B", "A"),
                                          ("S",) + ARR6_FLAT + ("N", "N", "N", "B", "N", "N", "N")), "queued"),
        FunctionSpec("Line", _motion_forms(("N", "N", "N", "B")), "queued"),
        FunctionSpec("Move_PTP", _motion_forms(("N", "N", "N", "B")), "queued"),
        FunctionSpec("Move_Line", _motion_forms(("N", "N", "N", "B")), "queued"),
        FunctionSpec("Circle", (("S", "A", "A", "N", "N", "N", "N", "B"),
                                ("S",) + ARR6_FLAT + ARR6_FLAT + ("N", "N", "N", "N", "B")), "queued"),
        FunctionSpec("PLine", _motion_forms(("N", "N", "N")), "queued"),
        FunctionSpec("Move_PLine", _motion_forms(("N", "N", "N")), "queued"),
        FunctionSpec("ChangeBase", (("S",), ("A",), ARR6_FLAT), "queued"),
        FunctionSpec("ChangeTCP", (("S",), ("A",), ("A", "N"), ("A", "N", "A"), ARR6_FLAT,
                                   ARR6_FLAT + ("N",), ARR6_FLAT + ("N",) * 10), "queued"),
        FunctionSpec("ChangeLoad", (("N",),), "queued"),
        FunctionSpec("QueueTag", (("N",), ("N", "N")), "blocking"),
        FunctionSpec("WaitQueueTag", (("N",), ("N", "N")), "blocking", returns="N"),
        FunctionSpec("StopAndClearBuffer", ((), ("N",)), "instant"),
        FunctionSpec("Pause", ((),), "instant"),
        FunctionSpec("Resume", ((),), "instant"),
        FunctionSpec("ScriptExit", ((), ("N",)), "blocking"),
        FunctionSpec("Sleep", (("N",),), "blocking"),
        FunctionSpec("ListenSend", (("N", "X"),), "instant", returns="N"),
        FunctionSpec("GetString", (("X",), ("X", "N"), ("X", "N", "N")), "instant", returns="S"),
        FunctionSpec("Length", (("X",),), "instant", returns="N"),
    )
}

PRIORITY_FUNCTIONS = {"scriptexit": (0, 1), "stopandclearbuffer": (0, 1, 2)}

# Read-only robot variables a script may read (spec §7 "Project variables can be read"); the
# emulator models the ones real clients read (pytmrobot state: Robot[0].*).
ROBOT_MEMBERS = {"coordrobot": "A", "coordbase": "A", "joint": "A", "tcpforce3d": "N",
                 "tcpspeed3d": "N", "basename": "S", "tcpname": "S", "payload": "N"}

# Digital I/O objects (TM Expression Editor manual 7.5 IO, p.222-224): IO["<module>"].<member>,
# the members the emulator models (lower case -> writable). Analog I/O and the Safety module are
# not modelled (ERROR). Modules and channel counts are checked when the script runs
# (builtins.io_channels).
IO_MEMBERS = {"di": False, "do": True, "instantdo": True}


def _is_io(expr: Expr) -> bool:
    """``IO[<module>]``."""
    return isinstance(expr, Index) and isinstance(expr.target, Name) and expr.target.name.lower() == "io"


def io_member(expr: Expr) -> Attr | None:
    """The ``IO[<module>].<member>`` of an expression that is one, else None."""
    return expr if isinstance(expr, Attr) and _is_io(expr.target) else None


# ----------------------------------------------------------------------------- static checks


class _Checker:
    """Static type check of one script against the session's declared variables."""

    def __init__(self, session_vars: dict[str, tuple[str, bool]]) -> None:
        self.vars = dict(session_vars)  # lower-case name -> (type, is_array)

    def kind_of(self, expr: Expr) -> str:
        """Return the static kind ("N", "S", "B", "A", "X") or raise ScriptSyntaxError."""
        if isinstance(expr, Num):
            return "N"
        if isinstance(expr, Str):
            return "S"
        if isinstance(expr, Bool):
            return "B"
        if isinstance(expr, ArrayLit):
            for item in expr.items:
                if self.kind_of(item) == "A":
                    raise ScriptSyntaxError("nested arrays")
            return "A"
        if isinstance(expr, Name):
            entry = self.vars.get(expr.name.lower())
            if entry is None:
                raise ScriptSyntaxError(f"undeclared variable {expr.name}")
            return "A" if entry[1] else _TYPE_KIND[entry[0]]
        if isinstance(expr, Index):
            if _is_io(expr):
                self.expect(expr.index, "S")
                return "X"
            self.expect(expr.index, "N")
            if isinstance(expr.target, Name) and expr.target.name.lower() == "robot":
                return "X"
            target = self.kind_of(expr.target)
            if target not in ("A", "X"):
                raise ScriptSyntaxError("indexing a non-array")
            if isinstance(expr.target, Name):
                return _TYPE_KIND[self.vars[expr.target.name.lower()][0]]
            return "X"
        if isinstance(expr, Attr):
            if _is_io(expr.target):
                self.kind_of(expr.target)
                if expr.name.lower() not in IO_MEMBERS:
                    raise ScriptSyntaxError(f"unknown IO member {expr.name}")
                return "A"
            if (isinstance(expr.target, Index) and isinstance(expr.target.target, Name)
                    and expr.target.target.name.lower() == "robot"):
                self.expect(expr.target.index, "N")
                kind = ROBOT_MEMBERS.get(expr.name.lower())
                if kind is None:
                    raise ScriptSyntaxError(f"unknown Robot member {expr.name}")
                return kind
            raise ScriptSyntaxError("unknown object")
        if isinstance(expr, Call):
            spec = FUNCTIONS.get(expr.name.lower())
            if spec is None or spec.name != expr.name:
                # Choice (§7): function names are case-sensitive as in the manual's signatures.
                raise ScriptSyntaxError(f"unknown function {expr.name}")
            kinds = [self.kind_of(a) for a in expr.args]
            if not any(_form_matches(form, kinds) for form in spec.forms):
                raise ScriptSyntaxError(f"{spec.name}: arguments do not match any form")
            return spec.returns
        if isinstance(expr, Unary):
            inner = self.kind_of(expr.operand)
            if expr.op == "!":
                return "B"
            if inner not in ("N", "X"):
                raise ScriptSyntaxError(f"unary {expr.op} on non-number")
            return "N"
        if isinstance(expr, Binary):
            left, right = self.kind_of(expr.left), self.kind_of(expr.right)
            if expr.op in ("&&", "||", "==", "!=", "<", ">", "<=", ">="):
                return "B"
            if expr.op == "+" and "S" in (left, right):
                return "S"
            for side in (left, right):
                if side not in ("N", "X"):
                    raise ScriptSyntaxError(f"operator {expr.op} on non-number")
            return "N"
        if isinstance(expr, Postfix):
            kind = self.kind_of(expr.target)
            if kind not in ("N", "X"):
                raise ScriptSyntaxError(f"{expr.op} on non-number")
            return "N"
        raise ScriptSyntaxError("unsupported expression")  # pragma: no cover

    def expect(self, expr: Expr, kind: str) -> None:
        if not _kind_ok(kind, self.kind_of(expr)):
            raise ScriptSyntaxError(f"expected {kind}")

    def statement(self, stmt: Statement) -> str | None:
        """Check ``stmt``; return the lower-case name it declares, if any."""
        if isinstance(stmt, Declare):
            key = stmt.name.lower()
            if key in self.vars:
                raise ScriptSyntaxError(f"{stmt.name} already declared")  # §4.1 re-declare -> ERROR
            if stmt.init is not None:
                got = self.kind_of(stmt.init)
                want = "A" if stmt.is_array else _TYPE_KIND[stmt.type_name]
                if not _assignable(want, got):
                    raise ScriptSyntaxError("initialiser type mismatch")
            self.vars[key] = (stmt.type_name, stmt.is_array)
            return key
        if isinstance(stmt, Assign):
            want = self.kind_of(stmt.target)
            if isinstance(stmt.target, Attr):
                raise ScriptSyntaxError("Robot members and whole IO arrays are read-only")
            io = io_member(stmt.target.target) if isinstance(stmt.target, Index) else None
            if io is not None and (not IO_MEMBERS[io.name.lower()] or stmt.op != "="):
                raise ScriptSyntaxError(f"IO {io.name} cannot be assigned this way")
            got = self.kind_of(stmt.value)
            if stmt.op != "=" and not (want in ("N", "X") or (want == "S" and stmt.op == "+=")):
                raise ScriptSyntaxError(f"{stmt.op} on non-number")
            if not _assignable(want, got):
                raise ScriptSyntaxError("assignment type mismatch")
            return None
        if isinstance(stmt, ExprStmt):
            self.kind_of(stmt.expr)
        return None


_TYPE_KIND = {"int": "N", "float": "N", "double": "N", "byte": "N", "string": "S", "bool": "B"}


def _kind_ok(want: str, got: str) -> bool:
    return want == "X" or got == "X" or want == got


def _assignable(want: str, got: str) -> bool:
    # Choice (§4.2 "string converted to number" is a warning, not an error): numbers and strings
    # convert both ways; bool/number convert; arrays only from arrays.
    if _kind_ok(want, got):
        return True
    if "A" in (want, got):
        return False
    return True


def _form_matches(form: tuple[str, ...], kinds: list[str]) -> bool:
    return len(form) == len(kinds) and all(_kind_ok(w, g) for w, g in zip(form, kinds))


def _priority_of(stmt: Statement, number: int) -> tuple[PriorityCommand | None, bool]:
    """Return (priority command, is_invalid_priority).  A priority call is ``ScriptExit(n)`` /
    ``StopAndClearBuffer(n)`` as a whole statement with one argument (spec §4.5)."""
    if not (isinstance(stmt, ExprStmt) and isinstance(stmt.expr, Call)):
        return None, False
    call = stmt.expr
    allowed = PRIORITY_FUNCTIONS.get(call.name.lower())
    if allowed is None or len(call.args) != 1 or FUNCTIONS[call.name.lower()].name != call.name:
        return None, False
    arg = call.args[0]
    if isinstance(arg, Num) and isinstance(arg.value, int) and arg.value in allowed:
        return PriorityCommand(FUNCTIONS[call.name.lower()].name, arg.value, number), False
    # §4.5: the argument must be a literal (StopAndClearBuffer(var_st) -> ERROR); an out-of-range
    # literal is an invalid argument too.
    return None, True


def split_lines(script: str) -> list[str]:
    """Split on CRLF (spec §4.1).  A trailing CRLF leaves an empty last line, which is dropped."""
    lines = script.split("\r\n")
    if len(lines) > 1 and lines[-1] == "":
        lines.pop()
    return lines


def parse_script(script: str, session_vars: dict[str, tuple[str, bool]] | None = None) -> ParsedScript:
    """Parse and statically check ``script`` (the text after ``ID,``)."""
    checker = _Checker(session_vars or {})
    lines: list[Line] = []
    errors: list[int] = []
    declared: list[str] = []
    priorities: list[PriorityCommand] = []
    if script == "":
        return ParsedScript((), ())  # §4.1: empty script (keep-alive) -> OK
    for number, text in enumerate(split_lines(script), start=1):
        try:
            if "\r" in text or "\n" in text:
                raise ScriptSyntaxError("bare CR or LF")  # §4.1: only CRLF separates lines
            stmt = parse_statement(text)
            priority, bad_priority = _priority_of(stmt, number)
            if bad_priority:
                raise ScriptSyntaxError("priority command needs a literal argument")
            if priority is not None:
                priorities.append(priority)
            name = checker.statement(stmt)
            if name is not None:
                declared.append(name)
            lines.append(Line(number, stmt))
        except ScriptSyntaxError:
            errors.append(number)
            lines.append(Line(number, Empty()))
    return ParsedScript(tuple(lines), tuple(errors), tuple(declared), _pick_priority(priorities))


def _pick_priority(found: Iterable[PriorityCommand]) -> PriorityCommand | None:
    """§4.5: ScriptExit wins over StopAndClearBuffer; of several of one kind the first counts."""
    found = list(found)
    for name in ("ScriptExit", "StopAndClearBuffer"):
        for command in found:
            if command.name == name:
                return command
    return None
