"""The ST syntax tree: frozen dataclasses, each with a source span kept out of equality.

Spans let diagnostics, faults, traces and breakpoints speak in ST lines; keeping them out of `==`
means reformatted source gives equal trees.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass, field

from stvm.source import NO_SPAN, Span, fast_frozen_init  # every node carries one (`n.Span`)


def _span() -> Span:
    return field(default=NO_SPAN, repr=False, compare=False)


_next_node_id = itertools.count(1).__next__


class Node:
    """A syntax node. `nid` is its stable identity, for the facts later stages keep about it.

    Nodes compare by value (two `x := 1;` are equal), so facts about one node cannot be keyed by
    the node itself; `id(node)` is reused once a node is freed, which forced holders of such maps
    to keep the nodes alive. Every node draws a number from one counter when it is made (in its
    `__init__`, see the end of this module) and keeps it for its life. It is not pickled: a node
    read back from a cache, a copy or a `dataclasses.replace` is a new node with a new number."""

    # The node classes are slotted dataclasses: no per-node __dict__ (memory).
    __slots__ = ("nid",)
    span: Span
    nid: int


# ---- expressions ---------------------------------------------------------------------------

class Expr(Node):
    __slots__ = ()


@dataclass(frozen=True, slots=True)
class IntLiteral(Expr):
    value: int
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class RealLiteral(Expr):
    value: float
    text: str
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class BoolLiteral(Expr):
    value: bool
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class StringLiteral(Expr):
    value: bytes
    double_quoted: bool = False
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class TimeLiteral(Expr):
    """T#…, D#…, TOD#…, DT#… as integer nanoseconds; `type_name` is TIME, DATE, TIME_OF_DAY or DATE_AND_TIME."""

    type_name: str
    value_ns: int
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class HashLiteral(Expr):
    """`Prefix#value`: a typed literal (INT#5) or an enumerator (Color#Red); semantics decides."""

    prefix: tuple[str, ...]
    rooted: bool
    text: str
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Name(Expr):
    parts: tuple[str, ...]
    rooted: bool = False
    span: Span = _span()

    @property
    def text(self) -> str:
        return ("\\\\" if self.rooted else "") + "\\".join(self.parts)


@dataclass(frozen=True, slots=True)
class Member(Expr):
    base: Expr
    name: str
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class BitAccess(Expr):
    base: Expr
    bit: int
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class PartialAccess(BitAccess):
    """`d.%B1`, `l.%W0`, `l.%D1`: part `bit` (counted from the least significant) of `width` bits.
    A BitAccess, so every walk over variable paths treats it as one (`w.%X3` is a BitAccess)."""

    width: int = 8


@dataclass(frozen=True, slots=True)
class Index(Expr):
    base: Expr
    indices: tuple[Expr, ...]
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Deref(Expr):
    base: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Argument(Node):
    """One call argument. kind: 'input' (`n := e`), 'output' (`n => v`), 'output_not' (`NOT n => v`), 'positional'."""

    kind: str
    name: str | None
    value: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Call(Expr):
    callee: Expr
    args: tuple[Argument, ...]
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class AssignExpr(Expr):
    """`target := value` used as an expression (CODESYS/TwinCAT): stores value, converted to the
    target's type, and has that value."""

    target: Expr
    value: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Unary(Expr):
    op: str
    operand: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Binary(Expr):
    op: str
    left: Expr
    right: Expr
    span: Span = _span()


# ---- statements ----------------------------------------------------------------------------

class Statement(Node):
    __slots__ = ()


@dataclass(frozen=True, slots=True)
class Assign(Statement):
    target: Expr
    value: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class RefAssign(Statement):
    """CODESYS `target REF= value`: bind the REFERENCE TO variable `target` to the variable `value`."""

    target: Expr
    value: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class CallStatement(Statement):
    call: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class If(Statement):
    branches: tuple[tuple[Expr, tuple[Statement, ...]], ...]
    else_body: tuple[Statement, ...] | None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class CaseLabel(Node):
    """A case label: a value, or a range when `high` is set. Values are IntLiteral, Name or HashLiteral."""

    low: Expr
    high: Expr | None = None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Case(Statement):
    selector: Expr
    elements: tuple[tuple[tuple[CaseLabel, ...], tuple[Statement, ...]], ...]
    else_body: tuple[Statement, ...] | None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class For(Statement):
    variable: Name
    start: Expr
    end: Expr
    step: Expr | None
    body: tuple[Statement, ...]
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class While(Statement):
    condition: Expr
    body: tuple[Statement, ...]
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Repeat(Statement):
    body: tuple[Statement, ...]
    condition: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Exit(Statement):
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Continue(Statement):
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Return(Statement):
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Empty(Statement):
    span: Span = _span()


# ---- type specifications and initialisers --------------------------------------------------

class TypeSpec(Node):
    __slots__ = ()


@dataclass(frozen=True, slots=True)
class NamedTypeSpec(TypeSpec):
    parts: tuple[str, ...]
    rooted: bool = False
    span: Span = _span()

    @property
    def text(self) -> str:
        return "\\".join(self.parts)


@dataclass(frozen=True, slots=True)
class StringTypeSpec(TypeSpec):
    size: Expr
    wide: bool = False
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class ArrayTypeSpec(TypeSpec):
    ranges: tuple[tuple[Expr, Expr] | None, ...]  # None = `*`
    element: TypeSpec
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class SubrangeTypeSpec(TypeSpec):
    base: str
    low: int
    high: int
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class RefTypeSpec(TypeSpec):
    target: TypeSpec
    flavour: str = "REF_TO"   # REF_TO (IEC), POINTER (POINTER TO), REFERENCE (REFERENCE TO)
    span: Span = _span()


class Initializer(Node):
    __slots__ = ()


@dataclass(frozen=True, slots=True)
class ExprInit(Initializer):
    expr: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class ArrayInit(Initializer):
    items: tuple[tuple[int, Initializer | None], ...]  # (repeat count, value) ; `3()` has value None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class StructInit(Initializer):
    items: tuple[tuple[str, Initializer], ...]
    span: Span = _span()


# ---- declarations --------------------------------------------------------------------------

@dataclass(frozen=True, slots=True)
class VarDecl(Node):
    names: tuple[tuple[str, Span], ...]
    type_spec: TypeSpec
    init: Initializer | None
    span: Span = _span()
    # CODESYS/TwinCAT `fb : F(1, nMax := 5)`: the arguments of F's FB_init (None: no parentheses)
    fb_args: tuple[Argument, ...] | None = None
    # the `{…}` pragmas right before the declaration, inside its var block (syntax/pragmas.py)
    pragmas: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class VarBlock(Node):
    kind: str  # VAR, VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR_TEMP, VAR_GLOBAL, VAR_EXTERNAL, VAR_STAT
    qualifiers: tuple[str, ...]
    decls: tuple[VarDecl, ...]
    span: Span = _span()

    @property
    def constant(self) -> bool:
        return "CONSTANT" in self.qualifiers


@dataclass(frozen=True, slots=True)
class StructDecl(Node):
    fields: tuple[VarDecl, ...]
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class UnionDecl(StructDecl):
    """CODESYS `UNION … END_UNION`: members that overlay the same bytes. A StructDecl, so every
    pass that looks at a struct's members (containment, nesting) sees a union's too."""


@dataclass(frozen=True, slots=True)
class EnumDecl(Node):
    members: tuple[tuple[str, int | None, Span], ...]
    base: str | None
    default: str | None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class AliasDecl(Node):
    type_spec: TypeSpec
    init: Initializer | None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class TypeDecl(Node):
    name: str
    namespace: tuple[str, ...]
    body: StructDecl | EnumDecl | AliasDecl
    span: Span = _span()
    pragmas: tuple[str, ...] = ()   # `{attribute 'qualified_only'}` … before it (syntax/pragmas.py)


@dataclass(frozen=True)
class Method(Node):
    """METHOD in a FUNCTION_BLOCK, PROGRAM or INTERFACE (IEC ed. 3 6.6.5); `modifiers`: PUBLIC,
    PRIVATE, PROTECTED, INTERNAL, ABSTRACT, FINAL, OVERRIDE as written (upper case)."""

    name: str
    modifiers: tuple[str, ...]
    return_type: TypeSpec | None
    var_blocks: tuple[VarBlock, ...]
    body: tuple[Statement, ...]
    pragmas: tuple[str, ...] = ()
    span: Span = _span()
    name_span: Span = _span()


@dataclass(frozen=True)
class Accessor(Node):
    """The GET or SET of a PROPERTY: its own variables and statements."""

    kind: str   # GET, SET
    var_blocks: tuple[VarBlock, ...]
    body: tuple[Statement, ...]
    span: Span = _span()


@dataclass(frozen=True)
class Property(Node):
    """PROPERTY P : T with GET and/or SET (CODESYS/TwinCAT)."""

    name: str
    modifiers: tuple[str, ...]
    type_spec: TypeSpec
    var_blocks: tuple[VarBlock, ...]
    getter: Accessor | None
    setter: Accessor | None
    pragmas: tuple[str, ...] = ()
    span: Span = _span()
    name_span: Span = _span()


@dataclass(frozen=True, slots=True)
class POU(Node):
    kind: str  # FUNCTION, FUNCTION_BLOCK, PROGRAM, INTERFACE
    name: str
    namespace: tuple[str, ...]
    return_type: TypeSpec | None
    var_blocks: tuple[VarBlock, ...]
    body: tuple[Statement, ...]
    pragmas: tuple[str, ...]
    span: Span = _span()
    end_span: Span = _span()
    modifiers: tuple[str, ...] = ()           # ABSTRACT, FINAL, PUBLIC, INTERNAL
    extends: tuple[Name, ...] = ()            # FB EXTENDS one base; INTERFACE EXTENDS several
    implements: tuple[Name, ...] = ()
    methods: tuple[Method, ...] = ()
    properties: tuple[Property, ...] = ()
    name_span: Span = _span()


@dataclass(frozen=True, slots=True)
class GlobalVars(Node):
    block: VarBlock
    namespace: tuple[str, ...]
    span: Span = _span()
    pragmas: tuple[str, ...] = ()   # attributes before VAR_GLOBAL (syntax/pragmas.py)
    gvl: str = ""                   # the name of its global variable list (TwinCAT/CODESYS GVL)


@dataclass(frozen=True, slots=True)
class TaskDecl(Node):
    name: str
    params: tuple[tuple[str, Expr], ...]
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class ProgramConfig(Node):
    instance: str
    task: str | None
    type_name: tuple[str, ...]
    args: tuple[Argument, ...]
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Resource(Node):
    name: str
    globals: tuple[VarBlock, ...]
    tasks: tuple[TaskDecl, ...]
    programs: tuple[ProgramConfig, ...]
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Configuration(Node):
    name: str
    globals: tuple[VarBlock, ...]
    resources: tuple[Resource, ...]
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class CompilationUnit:
    path: str
    types: tuple[TypeDecl, ...]
    pous: tuple[POU, ...]
    globals: tuple[GlobalVars, ...]
    configurations: tuple[Configuration, ...]
    namespace_names: tuple[tuple[str, Span], ...] = ()   # every NAMESPACE name as written
    member_bases: frozenset[str] = frozenset()   # lower-cased X of every `X.y` (semantics/qualified.py)


_set_node_id = Node.nid.__set__   # type: ignore[attr-defined]   # the slot's own setter


def _stamped_init(init):
    """`init`, then a new node id (for the node classes `fast_frozen_init` leaves alone)."""
    def __init__(self, *args, **kwargs):
        init(self, *args, **kwargs)
        _set_node_id(self, _next_node_id())
    __init__.__qualname__, __init__.__doc__ = init.__qualname__, init.__doc__
    return __init__


def _rebuilt(cls: type, state: tuple) -> Node:
    """A node of `cls` with these field values and a new id (unpickling, copying)."""
    node = object.__new__(cls)
    for name, value in state:
        object.__setattr__(node, name, value)
    _set_node_id(node, _next_node_id())
    return node


def _reduce_by_fields(self):
    return (_rebuilt, (type(self), tuple((f.name, getattr(self, f.name)) for f in dataclasses.fields(self))))


for _cls in list(globals().values()):
    if isinstance(_cls, type) and dataclasses.is_dataclass(_cls) and _cls.__module__ == __name__ \
            and _cls.__dataclass_params__.frozen:
        _init = _cls.__init__
        fast_frozen_init(_cls, stamp=(Node.nid, _next_node_id) if issubclass(_cls, Node) else None)
        if issubclass(_cls, Node) and _cls.__init__ is _init:
            _cls.__init__ = _stamped_init(_init)
            _cls.__reduce__ = _reduce_by_fields   # the id is not pickled (nor copied)
del _cls, _init


def _inline_span_pickling(cls: type) -> None:
    """Pickle a node of `cls` as its fields with its `span` spelled out as five values, rebuilt
    by a module-level `_unpickled_<Class>`, instead of as its constructor arguments with a Span
    object among them. A node's span is its own (half a million spans for a 100,000-line unit):
    as objects each cost a Python `__reduce__` call, a memo entry and its argument tuple, which
    was 40 % of pickling the parsed unit (the unit's cache entry, first load) and a third of
    reading it back. A span that is not a Span object (none is, today) pickles as before."""
    names = [f.name for f in dataclasses.fields(cls)]
    if "span" not in names:
        return
    at = names.index("span")
    scope = {"_cls": cls, "Span": Span}
    fields = [f"a{i}" for i in range(len(names))]
    ctor_args = [("Span(span_file, span_line, span_column, span_end_line, span_end_column)" if i == at else a)
                 for i, a in enumerate(fields)]
    params = [a for i, a in enumerate(fields) if i != at] + \
        ["span_file", "span_line", "span_column", "span_end_line", "span_end_column"]
    name = f"_unpickled_{cls.__name__}"
    exec(f"def {name}({', '.join(params)}):\n    return _cls({', '.join(ctor_args)})\n", scope)   # noqa: S102 (field names of our own classes)
    rebuild = scope[name]
    rebuild.__module__, rebuild.__qualname__ = __name__, name   # pickled by reference: stvm.syntax.nodes.<name>
    globals()[name] = rebuild
    plain = cls.__reduce__
    own = "".join(f"self.{f}, " for i, f in enumerate(names) if i != at)
    scope.update(_rebuild=rebuild, _plain=plain, _span_cls=Span)
    exec("def __reduce__(self):\n"
         "    span = self.span\n"
         "    if span.__class__ is not _span_cls:\n"
         "        return _plain(self)\n"
         f"    return (_rebuild, ({own}span.file, span.line, span.column, span.end_line, span.end_column))\n",
         scope)   # noqa: S102 (as above)
    reduce = scope["__reduce__"]
    reduce.__qualname__ = f"{cls.__qualname__}.__reduce__"
    cls.__reduce__ = reduce


for _cls in list(globals().values()):
    # only the classes whose pickled form is their constructor arguments (fast_frozen_init's):
    # those left with `_reduce_by_fields` rebuild through their fields (and a new id) as before
    if isinstance(_cls, type) and issubclass(_cls, Node) and dataclasses.is_dataclass(_cls) \
            and _cls.__module__ == __name__ and _cls.__dict__.get("__reduce__") not in (None, _reduce_by_fields):
        _inline_span_pickling(_cls)
del _cls
