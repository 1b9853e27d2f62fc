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
from stvm.syntax.walk import _FIELDS, _KIND, _LOOPS, LOOP_WEIGHT, _kind


def hot_uses(body) -> dict[str, float]:
    """Weighted uses by lower-case single-part name.

    A walk with a stack of (node, weight) in the order of a recursive visit (each node before
    the nodes inside it, fields in their declared order), so every count adds up its weights
    in the same order and comes out the same float: no Python call per node (this ran per POU
    on every load, a sixth of lowering a 100,000-line program)."""
    counts: dict[str, float] = {}
    get = counts.get
    stack: list = [(tuple(body), 1.0)]
    pop, push = stack.pop, stack.append
    fields_of, kind_of = _FIELDS, _KIND
    name_cls, if_cls, case_cls, call_cls = n.Name, n.If, n.Case, n.Call
    while stack:
        node, weight = pop()
        cls = node.__class__
        kind = kind_of.get(cls)
        if kind is None:
            kind = _kind(cls)
        if kind == 1:      # a tuple: its items, the first on top
            for i in range(len(node) - 1, -1, -1):
                push((node[i], weight))
            continue
        if kind == 0:
            continue
        if cls is name_cls:
            if len(node.parts) == 1:
                key = node.parts[0].lower()
                counts[key] = get(key, 0.0) + weight
            continue
        if cls is if_cls:
            # each condition is tested on most calls; each branch runs on one of len + 1 ways
            share = weight / (len(node.branches) + 1)
            if node.else_body is not None:
                push((node.else_body, share))
            for cond, stmts in reversed(node.branches):
                push((stmts, share))
                push((cond, weight))
            continue
        if cls is case_cls:
            share = weight / (len(node.elements) + 1)
            if node.else_body is not None:
                push((node.else_body, share))
            for _, stmts in reversed(node.elements):   # the labels are constants
                push((stmts, share))
            push((node.selector, weight))
            continue
        if cls is call_cls and node.callee.__class__ is name_cls and len(node.callee.parts) == 1:
            # an FB call names its instance once per argument it passes or reads back, and once
            # to call it (a FUNCTION's name is no variable: counting it changes nothing)
            key = node.callee.parts[0].lower()
            counts[key] = get(key, 0.0) + weight * len(node.args)
        elif cls in _LOOPS:
            weight *= LOOP_WEIGHT
        names = fields_of[cls]
        for i in range(len(names) - 1, -1, -1):
            push((getattr(node, names[i]), weight))
    return counts
