"""What the checker records for the code generator, per expression node: its type, what a name
refers to, how a call binds (`Facts`). The body checker fills them; the lowering and the debugger
read them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from stvm.semantics import types as t
from stvm.semantics.model import POUInfo, Variable
from stvm.syntax import nodes as n

# the value of a constant expression that is not one (compile-time folding)
NOT_CONST = object()


@dataclass
class NameRef:
    """What a `Name` expression denotes."""

    kind: str                     # 'var', 'global', 'enum', 'const', 'pou', 'result'
    variable: Variable | None = None
    pou: POUInfo | None = None
    value: object = None          # enum value / constant


@dataclass
class CallInfo:
    """A resolved call: the callee and how each argument binds."""

    pou: POUInfo
    is_fb: bool
    instance: n.Expr | None       # the FB instance expression
    inputs: list[tuple[Variable, n.Expr]] = field(default_factory=list)
    outputs: list[tuple[Variable, n.Expr, bool]] = field(default_factory=list)   # (pin, target, negate)
    extra: list[n.Expr] = field(default_factory=list)     # variadic extras, in order
    generic_type: t.Type | None = None
    arg_types: tuple[t.Type, ...] = ()                    # per parameter (+ extras), for typed natives
    en: n.Expr | None = None                              # `EN := c`: the call runs only when c is TRUE
    eno: tuple[n.Expr, bool] | None = None                # `ENO => v` / `NOT ENO => v`: (target, negate)
    nested_en: bool = False                               # EN/ENO on a call inside a larger expression
    # a METHOD call: 'self' (own method, `M()` / `THIS^.M()`), 'inst' (`fb.M()`), 'super'
    # (`SUPER^.M()`, static), 'itf' (through an interface variable); 'super_body' is `SUPER^()`
    oo: str = ""
    static_owner: str = ""                                # 'super'/'super_body': the base FB's key


@dataclass
class Facts:
    """Every map is keyed by the node's `nid` (stvm/syntax/nodes.py): nodes compare by value, so
    two equal expressions in different places need different keys, and a nid, unlike `id()`, is
    never reused while the node lives elsewhere."""

    types: dict[int, t.Type] = field(default_factory=dict)
    names: dict[int, NameRef] = field(default_factory=dict)
    calls: dict[int, CallInfo] = field(default_factory=dict)
    untyped: set[int] = field(default_factory=set)        # untyped numeric literals (after folding)
    consts: dict[int, object] = field(default_factory=dict)  # compile-time values of constant exprs
    array_from_element: set[int] = field(default_factory=set)  # Index exprs passed as "array from here"
    operand_types: dict[int, t.Type] = field(default_factory=dict)  # comparisons: the type compared in
    ref_calls: set[int] = field(default_factory=set)      # REF(x) / ADR(x) calls
    # LOWER_BOUND/UPPER_BOUND/SIZEOF calls: ("CONST", value) or (word, ARRAY[*] operand)
    type_queries: dict[int, tuple[str, object]] = field(default_factory=dict)
    auto_deref: set[int] = field(default_factory=set)     # names of REFERENCE TO variables (used as the target)
    addressed: set[tuple[str, str]] = field(default_factory=set)  # (POU key, variable key) whose reference is taken
    props: dict[int, tuple] = field(default_factory=dict)  # property uses: nid → (PropertyInfo, how) how: self/inst/itf
    intrinsics: dict[int, tuple] = field(default_factory=dict)  # __QUERYINTERFACE ('query', key) / __ISVALIDREF ('valid', None)
