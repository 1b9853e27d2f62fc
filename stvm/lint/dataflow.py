"""A forward dataflow solver over a POU's CFG, with the PLC scan as the outer loop.

A PLC calls a PROGRAM or FB instance once per scan, and its persistent variables carry over, so
the state at the start of a call is the initial state joined with whatever a previous call
left at its end. `solve` models exactly that: the entry state is
`initial ⊔ next_call(exit state)`, iterated to a fixpoint together with the body's own loops.
Widening is applied at the entry and at loop heads, after a few plain joins, so integer
ranges settle on program constants instead of creeping one step per iteration.

An analysis supplies the lattice (`join`, `widen`, `leq`) and the transfer functions; a state
of `None` means "unreachable".
"""

from __future__ import annotations

import heapq
from typing import Generic, Protocol, TypeVar

from stvm.lint.cfg import CFG, Edge, Node

S = TypeVar("S")

_PLAIN_JOINS = 3   # joins at a loop head before widening starts
_PLAIN_JOINS_ENTRY = 1   # at the call entry (the scan loop): each pass re-runs the whole body


class ForwardAnalysis(Protocol[S]):
    def initial(self) -> S: ...
    def next_call(self, exit_state: S) -> S: ...
    def transfer(self, node: Node, state: S) -> S: ...
    def edge(self, edge: Edge, state: S) -> S | None: ...
    def join(self, a: S, b: S) -> S: ...
    def widen(self, old: S, new: S, rounds: int = 1, at: Node | None = None) -> S: ...
    def leq(self, a: S, b: S) -> bool: ...


class Solution(Generic[S]):
    """`before[node]`: the state on entry to the node (None: the node is never reached)."""

    def __init__(self, cfg: CFG, before: dict[int, S | None], feasible: set[int]) -> None:
        self.cfg = cfg
        self.before = before
        self.feasible = feasible   # ids of edges some state took (states only grow: = at the fixpoint)

    def at(self, node: Node) -> S | None:
        return self.before.get(node.index)

    def reachable(self, node: Node) -> bool:
        return self.before.get(node.index) is not None


def solve(cfg: CFG, analysis: ForwardAnalysis[S], scan_loop: bool = True,
          record_edges: bool = False, narrow: int = 0) -> Solution[S]:
    """Solve to the fixpoint; `record_edges`: collect the ids of the edges some state took;
    `narrow`: passes of plain re-evaluation after widening (each keeps a sound result and
    takes back what widening gave away, e.g. `r := i` inside `FOR i := 0 TO 7`)."""
    order = cfg.rpo()
    position = {node.index: i for i, node in enumerate(order)}
    before: dict[int, S | None] = {node.index: None for node in cfg.nodes}
    visits: dict[int, int] = {}
    widen_at = {node.index for node in cfg.nodes if node.loop_head}
    if scan_loop:
        widen_at.add(cfg.entry.index)
    before[cfg.entry.index] = analysis.initial()
    initial = before[cfg.entry.index]
    # worklist ordered by reverse post-order: inner nodes settle before their loop heads re-run
    feasible: set[int] = set()
    heap = [position[cfg.entry.index]]
    queued = {cfg.entry.index}

    def push(index: int) -> None:
        if index not in queued:
            queued.add(index)
            heapq.heappush(heap, position[index])

    def offer(target: Node, state: S) -> None:
        old = before[target.index]
        if old is None:
            before[target.index] = state
            push(target.index)
            return
        if analysis.leq(state, old):
            return
        merged = analysis.join(old, state)
        if target.index in widen_at:
            count = visits.get(target.index, 0) + 1
            visits[target.index] = count
            plain = _PLAIN_JOINS_ENTRY if target is cfg.entry else _PLAIN_JOINS
            if count > plain:
                # `rounds`: the how-many-th widening at this point; the analysis widens to program
                # constants first and to the declared limits after a few rounds, so a counter
                # does not climb threshold by threshold
                merged = analysis.widen(old, merged, count - plain, target)
        before[target.index] = merged
        push(target.index)

    while heap:
        node = order[heapq.heappop(heap)]
        index = node.index
        queued.discard(index)
        state = before[index]
        if state is None:
            continue
        after = analysis.transfer(node, state)
        for edge in node.succs:
            out = analysis.edge(edge, after)
            if out is not None:
                if record_edges:
                    feasible.add(id(edge))
                offer(edge.dst, out)
        if node is cfg.exit and scan_loop:
            offer(cfg.entry, analysis.join(initial, analysis.next_call(after)))
    for _ in range(narrow):
        feasible = set()
        outputs: dict[int, S | None] = {}
        for node in order:
            index = node.index
            incoming = []
            if node is cfg.entry:
                incoming.append(initial)
            for edge in node.preds:
                src = edge.src.index
                if before[src] is None:
                    continue
                if src not in outputs:
                    outputs[src] = analysis.transfer(edge.src, before[src])
                out = analysis.edge(edge, outputs[src])
                if out is not None:
                    feasible.add(id(edge))
                    incoming.append(out)
            if node is cfg.entry and scan_loop and before[cfg.exit.index] is not None:
                incoming.append(analysis.next_call(analysis.transfer(cfg.exit, before[cfg.exit.index])))
            state = None
            for item in incoming:
                state = item if state is None else analysis.join(state, item)
            before[index] = state
            outputs.pop(index, None)
    return Solution(cfg, before, feasible)
