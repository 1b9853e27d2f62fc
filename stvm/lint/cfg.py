"""Control-flow graph of one POU body: one node per simple statement, conditions on the edges.

The graph models one *call* of the POU (one scan for a PROGRAM). `entry` and `exit` are the
call's start and end; the dataflow solver adds the scan back edge (exit → entry) itself, because
what crosses it depends on the analysis (persistent variables keep their values, inputs do not).

Node kinds:

| kind       | what                                              | fields                      |
|------------|---------------------------------------------------|-----------------------------|
| entry/exit | start and end of the call                         |                             |
| assign     | `target := value`                                 | stmt (n.Assign)             |
| call       | a call statement                                  | stmt (n.CallStatement)      |
| branch     | an IF/ELSIF/WHILE/UNTIL condition (2 edges)       | stmt, expr (the condition)  |
| case       | a CASE selector (one edge per element + else)     | stmt (n.Case), expr         |
| for_init   | `var := start` of a FOR                           | stmt (n.For)                |
| for_test   | a FOR test `var <= end` (or `>=`): the first one, | stmt (n.For)                |
|            | then the loop head after each step                |                             |
| for_step   | `var := var + step`                               | stmt (n.For)                |
| join       | where branches meet (no effect)                   |                             |

Edge labels: None (plain), ("true", cond) / ("false", cond), ("case", labels) for one CASE
element, ("else", all labels) for the CASE's ELSE (also taken when there is no ELSE), and
("for_in", for) / ("for_out", for) on the two edges of a FOR head.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from stvm.syntax import nodes as n


@dataclass(eq=False)
class Edge:
    src: "Node"
    dst: "Node"
    label: tuple | None = None


@dataclass(eq=False)
class Node:
    index: int
    kind: str
    stmt: n.Statement | None = None
    expr: n.Expr | None = None
    succs: list[Edge] = field(default_factory=list)
    preds: list[Edge] = field(default_factory=list)
    loop_head: bool = False

    @property
    def span(self) -> n.Span | None:
        if self.expr is not None and self.kind in ("branch", "case"):
            return self.expr.span
        return self.stmt.span if self.stmt is not None else None

    def __repr__(self) -> str:
        line = self.span.line if self.span is not None else "-"
        return f"<{self.kind}#{self.index} l.{line}>"


@dataclass
class CFG:
    pou: n.POU
    nodes: list[Node]
    entry: Node
    exit: Node
    _rpo: list[Node] | None = field(default=None, repr=False)

    def rpo(self) -> list[Node]:
        """Nodes in reverse post-order from the entry (unreachable nodes last, in creation order)."""
        if self._rpo is None:
            self._rpo = self._compute_rpo()
        return self._rpo

    def _compute_rpo(self) -> list[Node]:
        seen: set[int] = set()
        order: list[Node] = []
        stack: list[tuple[Node, int]] = [(self.entry, 0)]
        seen.add(self.entry.index)
        while stack:
            node, i = stack.pop()
            if i < len(node.succs):
                stack.append((node, i + 1))
                nxt = node.succs[i].dst
                if nxt.index not in seen:
                    seen.add(nxt.index)
                    stack.append((nxt, 0))
            else:
                order.append(node)
        order.reverse()
        order += [node for node in self.nodes if node.index not in seen]
        return order


class _Builder:
    def __init__(self, pou: n.POU) -> None:
        self.pou = pou
        self.nodes: list[Node] = []
        self.entry = self.new("entry")
        self.exit = self.new("exit")
        # (exit target, continue target) of the enclosing loops
        self.loops: list[tuple[Node, Node]] = []

    def new(self, kind: str, stmt: n.Statement | None = None, expr: n.Expr | None = None) -> Node:
        node = Node(len(self.nodes), kind, stmt, expr)
        self.nodes.append(node)
        return node

    @staticmethod
    def link(src: Node, dst: Node, label: tuple | None = None) -> None:
        edge = Edge(src, dst, label)
        src.succs.append(edge)
        dst.preds.append(edge)

    def build(self) -> CFG:
        tails = self.block(self.pou.body, [(self.entry, None)])
        for node, label in tails:
            self.link(node, self.exit, label)
        return CFG(self.pou, self.nodes, self.entry, self.exit)

    # A "tail" is (node, label): a dangling edge still to be linked to the next statement.
    def block(self, body, tails: list[tuple[Node, tuple | None]]) -> list[tuple[Node, tuple | None]]:
        for stmt in body:
            tails = self.statement(stmt, tails)
        return tails

    def attach(self, tails, node: Node) -> None:
        for src, label in tails:
            self.link(src, node, label)

    def statement(self, s: n.Statement, tails):
        if isinstance(s, (n.Assign, n.CallStatement)):
            node = self.new("assign" if isinstance(s, n.Assign) else "call", s)
            self.attach(tails, node)
            return [(node, None)]
        if isinstance(s, n.If):
            out = []
            for cond, body in s.branches:
                test = self.new("branch", s, cond)
                self.attach(tails, test)
                out += self.block(body, [(test, ("true", cond))])
                tails = [(test, ("false", cond))]
            if s.else_body is not None:
                tails = self.block(s.else_body, tails)
            return out + tails
        if isinstance(s, n.Case):
            test = self.new("case", s, s.selector)
            self.attach(tails, test)
            out = []
            all_labels: list[n.CaseLabel] = []
            for labels, body in s.elements:
                all_labels += labels
                out += self.block(body, [(test, ("case", tuple(labels)))])
            else_tails = [(test, ("else", tuple(all_labels)))]
            if s.else_body is not None:
                else_tails = self.block(s.else_body, else_tails)
            return out + else_tails
        if isinstance(s, n.For):
            # two tests: the first (straight from the init: a loop whose start is within its end
            # runs its body at least once) and the loop head (after each step)
            init = self.new("for_init", s)
            self.attach(tails, init)
            first = self.new("for_test", s)
            self.link(init, first)
            head = self.new("for_test", s)
            head.loop_head = True
            step = self.new("for_step", s)
            after = self.new("join", s)
            body = self.new("join", s)
            self.link(first, body, ("for_in", s))
            self.link(first, after, ("for_out", s))
            self.link(head, body, ("for_in", s))
            self.link(head, after, ("for_out", s))
            self.loops.append((after, step))
            body_tails = self.block(s.body, [(body, None)])
            self.loops.pop()
            self.attach(body_tails, step)
            self.link(step, head)
            return [(after, None)]
        if isinstance(s, n.While):
            head = self.new("branch", s, s.condition)
            head.loop_head = True
            self.attach(tails, head)
            after = self.new("join", s)
            self.loops.append((after, head))
            body_tails = self.block(s.body, [(head, ("true", s.condition))])
            self.loops.pop()
            self.attach(body_tails, head)
            self.link(head, after, ("false", s.condition))
            return [(after, None)]
        if isinstance(s, n.Repeat):
            start = self.new("join", s)
            start.loop_head = True
            self.attach(tails, start)
            after = self.new("join", s)
            test = self.new("branch", s, s.condition)
            self.loops.append((after, test))
            body_tails = self.block(s.body, [(start, None)])
            self.loops.pop()
            self.attach(body_tails, test)
            self.link(test, after, ("true", s.condition))
            self.link(test, start, ("false", s.condition))
            return [(after, None)]
        if isinstance(s, n.Exit):
            if self.loops:
                self.attach(tails, self.loops[-1][0])
            return []
        if isinstance(s, n.Continue):
            if self.loops:
                self.attach(tails, self.loops[-1][1])
            return []
        if isinstance(s, n.Return):
            self.attach(tails, self.exit)
            return []
        return tails  # Empty


def build_cfg(pou: n.POU) -> CFG:
    """The control-flow graph of `pou`'s body (the checker has accepted it)."""
    return _Builder(pou).build()
