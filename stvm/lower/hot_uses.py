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
from stvm.syntax.walk import LOOP_WEIGHT


def hot_uses(body) -> dict[str, float]:
    """Weighted uses by lower-case single-part name."""
    counts: dict[str, float] = {}

    def visit(node, weight: float) -> None:
        if isinstance(node, tuple):
            for item in node:
                visit(item, weight)
            return
        if isinstance(node, n.Name):
            if len(node.parts) == 1:
                key = node.parts[0].lower()
                counts[key] = counts.get(key, 0.0) + weight
            return
        if isinstance(node, n.If):
            # each condition is tested on most calls; each branch runs on one of len + 1 ways
            share = weight / (len(node.branches) + 1)
            for cond, stmts in node.branches:
                visit(cond, weight)
                visit(stmts, share)
            if node.else_body is not None:
                visit(node.else_body, share)
            return
        if isinstance(node, n.Case):
            visit(node.selector, weight)
            share = weight / (len(node.elements) + 1)
            for _, stmts in node.elements:   # the labels are constants
                visit(stmts, share)
            if node.else_body is not None:
                visit(node.else_body, share)
            return
        if isinstance(node, n.Call) and isinstance(node.callee, n.Name) and len(node.callee.parts) == 1:
            # an FB call names its instance once per argument it passes or reads back, and once
            # to call it (a FUNCTION's name is no variable: counting it changes nothing)
            key = node.callee.parts[0].lower()
            counts[key] = counts.get(key, 0.0) + weight * len(node.args)
        if isinstance(node, (n.For, n.While, n.Repeat)):
            weight *= LOOP_WEIGHT
        for name in getattr(node, "__dataclass_fields__", ()):
            if name != "span":
                value = getattr(node, name)
                if isinstance(value, tuple) or hasattr(value, "__dataclass_fields__"):
                    visit(value, weight)

    visit(tuple(body), 1.0)
    del visit   # the closure refers to itself: break the cycle (no garbage for the collector)
    return counts

