"""Walks over the AST (stvm.syntax.nodes): every node under a statement list, the calls in it,
the variable at the root of an access path. The checker and the lowering both use them.
"""

from __future__ import annotations

from stvm.syntax import nodes as n

LOOP_WEIGHT = 10


def name_uses(body) -> dict[str, int]:
    """How often each single-part name is used in a statement list, loops weighted."""
    counts: dict[str, int] = {}

    def visit(node, weight: int) -> None:
        if isinstance(node, tuple):
            for item in node:
                visit(item, weight)
            return
        if isinstance(node, n.Name) and len(node.parts) == 1:
            key = node.parts[0].lower()
            counts[key] = counts.get(key, 0) + weight
        inner = weight * LOOP_WEIGHT if isinstance(node, (n.For, n.While, n.Repeat)) else weight
        for name in getattr(node, "__dataclass_fields__", ()):
            if name != "span":
                value = getattr(node, name)
                if isinstance(value, tuple) or hasattr(value, "__dataclass_fields__"):
                    visit(value, inner)

    visit(tuple(body), 1)
    return counts


def walk(body):
    """Every node under a statement list (statements, expressions, arguments)."""
    stack: list = list(body)
    while stack:
        node = stack.pop()
        if isinstance(node, tuple):
            stack.extend(node)
            continue
        yield node
        for name in getattr(node, "__dataclass_fields__", ()):
            if name != "span":
                value = getattr(node, name)
                if isinstance(value, tuple) or hasattr(value, "__dataclass_fields__"):
                    stack.append(value)


def root_name(expr) -> str | None:
    """The variable at the root of an access path (`a` in `a.b[1]`), lower case."""
    while isinstance(expr, (n.Member, n.Index, n.BitAccess)):
        expr = expr.base
    return expr.parts[0].lower() if isinstance(expr, n.Name) and len(expr.parts) == 1 else None


def calls_in(body) -> list[n.Call]:
    """Every Call node in a statement list (for the by-reference analysis)."""
    return [node for node in walk(body) if isinstance(node, n.Call)]
