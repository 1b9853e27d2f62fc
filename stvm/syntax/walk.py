"""Walks over the AST (stvm.syntax.nodes): every node under a statement list, the calls in it,
the variable at the root of an access path. The checker and the lowering both use them.
"""

from __future__ import annotations

import re
from operator import attrgetter

from stvm.syntax import nodes as n

LOOP_WEIGHT = 10


def name_uses(body) -> dict[str, int]:
    """How often each single-part name is used in a statement list, loops weighted."""
    counts: dict[str, int] = {}
    get = counts.get
    stack: list = [(node, 1) for node in body]
    pop, push = stack.pop, stack.append
    fields_of, kind_of = _FIELDS, _KIND
    name_cls, loops = n.Name, _LOOPS
    while stack:
        node, weight = pop()
        cls = node.__class__
        kind = kind_of.get(cls)
        if kind is None:
            kind = _kind(cls)
        if kind == 1:
            for item in node:
                push((item, weight))
            continue
        if kind == 0:
            continue
        if cls is name_cls and len(node.parts) == 1:
            key = node.parts[0].lower()
            counts[key] = get(key, 0) + weight
        if cls in loops:
            weight *= LOOP_WEIGHT
        for name in fields_of[cls]:
            push((getattr(node, name), weight))
    return counts


def walk(body):
    """Every node under a statement list (statements, expressions, arguments), each before the
    nodes inside it (a stack: the last child first)."""
    stack: list = list(body)
    pop, push, extend = stack.pop, stack.append, stack.extend
    fields_of, kind_of = _FIELDS, _KIND
    while stack:
        node = pop()
        cls = node.__class__
        kind = kind_of.get(cls)
        if kind is None:
            kind = _kind(cls)
        if kind == 1:
            extend(node)
            continue
        if kind == 0:
            continue
        yield node
        for name in fields_of[cls]:
            push(getattr(node, name))


def root_name(expr) -> str | None:
    """The variable at the root of an access path (`a` in `a.b[1]`), lower case."""
    while isinstance(expr, (n.Member, n.Index, n.BitAccess)):
        expr = expr.base
    return expr.parts[0].lower() if isinstance(expr, n.Name) and len(expr.parts) == 1 else None


_FIELDS: dict[type, tuple[str, ...]] = {}   # per node class: the fields that can hold nodes
_KIND: dict[type, int] = {}                 # 0: not a node, 1: tuple (splice), 2: node
_LOOPS = (n.For, n.While, n.Repeat)


def _kind(cls) -> int:
    if issubclass(cls, tuple):
        kind = 1
    elif hasattr(cls, "__dataclass_fields__"):
        kind = 2
        _FIELDS[cls] = node_fields(cls)
    else:
        kind = 0
    _KIND[cls] = kind
    return kind


_WALK_GETTERS: dict[type, object] = {}   # per node class: its fields that can hold a Call (attrgetter)
_WALK_KIND: dict[type, int] = {}   # 0: skip (no Call can be inside), 1: tuple (splice), 2: node of
                                   # several such fields (visit), 3: node of one (visit)


def _walk_kind(cls) -> int:
    if issubclass(cls, tuple):
        return 1
    if hasattr(cls, "__dataclass_fields__"):
        names = node_fields(cls)
        if issubclass(cls, n.Call) or names:
            _WALK_GETTERS[cls] = attrgetter(*names) if names else (lambda node: ())
            return 3 if len(names) == 1 else 2
    return 0


_SCALARS = {"str", "int", "bool", "float", "bytes", "None", "Span", "n.Span"}


def node_fields(cls) -> tuple[str, ...]:
    """The fields of a node class that can hold nodes: not `span`, and not declared as only
    scalars (str, int, tuples of str, …), whose values never hold a Call."""
    out = []
    for name, f in cls.__dataclass_fields__.items():
        if name == "span":
            continue
        kind = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", "?")
        atoms = set(re.findall(r"[A-Za-z_][A-Za-z0-9_.]*", kind)) - {"tuple"}
        if atoms and atoms <= _SCALARS:
            continue
        out.append(name)
    return tuple(out)


def calls_in(body) -> list[n.Call]:
    """Every Call node under a statement list, in the order of `walk` (a stack: the last child
    first), without its per-node reflection (the checker and the lowering call it per POU). A
    node's fields are read by one `attrgetter` call and all pushed: those that cannot hold a
    Call are dropped when popped, which keeps the order and saves a Python loop per node."""
    out: list[n.Call] = []
    stack: list = list(body)
    pop, push, extend = stack.pop, stack.append, stack.extend
    getters, kind_of = _WALK_GETTERS, _WALK_KIND
    call_cls = n.Call
    while stack:
        node = pop()
        cls = node.__class__
        kind = kind_of.get(cls)
        if kind is None:
            kind = kind_of[cls] = _walk_kind(cls)
        if kind == 1:
            extend(node)
            continue
        if kind == 0:
            continue
        if isinstance(node, call_cls):
            out.append(node)
        if kind == 3:
            push(getters[cls](node))
        else:
            extend(getters[cls](node))
    return out
