"""How often a call is expected to touch each variable: uses weighted by the branches they sit in.

`name_uses` counts every use in a body alike, so a variable named in each of the fourteen steps of
a CASE step machine counts fourteen times although one call runs one step. Caching such a
variable in a Python local costs a load on entry and a store on exit on every call, and most calls
(an FB waiting for its Execute edge) run none of those steps. `hot_uses` divides the weight of a
use by the number of ways its enclosing IF or CASE can go, so the count approximates the uses one
call makes; uses inside loops are multiplied (as in `name_uses`).

Only a heuristic for the lowering's `hot_path_cache` option: which variables live in Python locals
never changes what the program computes, only how fast it runs.
"""

from __future__ import annotations

from stvm.syntax import nodes as n
from stvm.syntax.walk import LOOP_WEIGHT, node_fields


def hot_uses(body) -> dict[str, float]:
    """Weighted uses by lower-case single-part name. Each node class's fields are looked up once
    (`child_fields`), not asked of every node (`__dataclass_fields__`, `hasattr` per value):
    0.13 s instead of 0.20 s of the 0.53 s analysis pass of a 100,000-line program
    (bench/bench_large.py)."""
    counts: dict[str, float] = {}
    get = counts.get
    fields_of, unknown = CHILD_FIELDS, _UNKNOWN
    name_cls, if_cls, case_cls, call_cls, loops = n.Name, n.If, n.Case, n.Call, _LOOPS

    def visit(node, weight: float) -> None:
        cls = node.__class__
        names = fields_of.get(cls, unknown)
        if names is unknown:
            names = child_fields(cls)
        if names is None:   # a tuple or a scalar
            if isinstance(node, tuple):
                for item in node:
                    visit(item, weight)
            return
        if cls is name_cls:
            if len(node.parts) == 1:
                key = node.parts[0].lower()
                counts[key] = get(key, 0.0) + weight
            return
        if cls is if_cls:
            # each condition is tested on most calls; each branch runs on one of len + 1 ways
            share = weight / (len(node.branches) + 1)
            for cond, stmts in node.branches:
                visit(cond, weight)
                visit(stmts, share)
            if node.else_body is not None:
                visit(node.else_body, share)
            return
        if cls is case_cls:
            visit(node.selector, weight)
            share = weight / (len(node.elements) + 1)
            for _, stmts in node.elements:   # the labels are constants
                visit(stmts, share)
            if node.else_body is not None:
                visit(node.else_body, share)
            return
        if cls is call_cls and node.callee.__class__ is name_cls and len(node.callee.parts) == 1:
            # an FB call names its instance once per argument it passes or reads back, and once
            # to call it (a FUNCTION's name is no variable: counting it changes nothing)
            key = node.callee.parts[0].lower()
            counts[key] = get(key, 0.0) + weight * len(node.args)
        if cls in loops:
            weight *= LOOP_WEIGHT
        for name in names:
            visit(getattr(node, name), weight)

    visit(tuple(body), 1.0)
    del visit   # the closure refers to itself: break the cycle (no garbage for the collector)
    return counts


_UNKNOWN = object()
_LOOPS = frozenset({n.For, n.While, n.Repeat})
CHILD_FIELDS: dict[type, tuple[str, ...] | None] = {}
"""Per class met in a walk: `child_fields` of it (the lowering's walks over bodies read it)."""


def child_fields(cls) -> tuple[str, ...] | None:
    """The fields of a node class that may hold nodes (`stvm.syntax.walk.node_fields`: not
    `span`, not declared as only scalars); None for tuples and scalars. Remembered in
    `CHILD_FIELDS`."""
    names = node_fields(cls) if hasattr(cls, "__dataclass_fields__") else None
    CHILD_FIELDS[cls] = names
    return names
