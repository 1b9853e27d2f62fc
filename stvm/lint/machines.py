"""Step sequences (`CASE step OF …`) and the resources they hold between scans.

A *step machine* is a CASE whose selector is a persistent variable S that the branches assign
(`S := 30`, `S := S - 10`): each branch is a step, run once per scan while S holds its label.

The typestate analysis follows, per path and across scans, tuples

    (s, held, error, moved, assumed)

* `s`: S's value (None: unknown); a CASE edge keeps only the tuples whose `s` matches its labels;
* `held`: whether the resource is held (a socket opened, a flag set), changed by its
  acquire/release events;
* `error`: the node where this scan raised an error flag that ends the sequence (an
  `…Error…`/`…Done…` BOOL set TRUE that the machine itself never reads — the caller or the
  surrounding state diagram reacts to it, and the steps stop running);
* `moved`: S was assigned after that error (the path goes on to another step);
* `assumed`: PLCopen outputs (`fb.Done`, `fb.Error`, …) this scan's path assumed TRUE; they
  exclude each other, so `IF fb.Done … IF fb.Error …` cannot take both branches.

A scan that ends with `held` and an `error`, without moving to a step from which the release is
reachable, leaves the resource held with nobody to release it: that error node is a leak.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from stvm.lint.access import node_accesses
from stvm.lint.context import PouContext
from stvm.lint.dataflow import solve
from stvm.lint.facts_view import node_calls, place_key
from stvm.lint.intervals import is_point
from stvm.semantics import types as t
from stvm.semantics.model import EXTERNAL, GLOBAL, IN_OUT, LOCAL, OUTPUT
from stvm.syntax import nodes as n

_EXCLUSIVE = ("done", "busy", "error", "commandaborted")


@dataclass
class Machine:
    var: object                 # the Variable S
    case: n.Case
    case_node: object           # its CFG node
    inside: set[int]            # CFG node indices inside the CASE's branches
    branch_of: dict[int, tuple[int, ...]] = field(default_factory=dict)   # node index → state values
    transitions: dict[int, set[int]] = field(default_factory=dict)        # state → assigned states

    @property
    def key(self) -> str:
        return self.var.key


def _statements(body):
    for stmt in body:
        yield stmt
        if isinstance(stmt, n.If):
            for _, inner in stmt.branches:
                yield from _statements(inner)
            if stmt.else_body:
                yield from _statements(stmt.else_body)
        elif isinstance(stmt, n.Case):
            for _, inner in stmt.elements:
                yield from _statements(inner)
            if stmt.else_body:
                yield from _statements(stmt.else_body)
        elif isinstance(stmt, (n.For, n.While, n.Repeat)):
            yield from _statements(stmt.body)


def _label_values(ctx: PouContext, labels) -> tuple[int, ...]:
    out = []
    for label in labels:
        lo = ctx.facts.const(label.low)
        hi = ctx.facts.const(label.high) if label.high is not None else lo
        if isinstance(lo, int) and isinstance(hi, int) and hi - lo < 1000:
            out += range(lo, hi + 1)
    return tuple(out)


def step_machines(ctx: PouContext) -> list[Machine]:
    """The POU's step machines (computed once per POU context)."""
    cached = getattr(ctx, "_machines", None)
    if cached is None:
        cached = ctx._machines = _step_machines(ctx)
    return cached


def _step_machines(ctx: PouContext) -> list[Machine]:
    if ctx.info.kind == "FUNCTION":
        return []
    by_stmt: dict[int, list] = {}
    for node in ctx.cfg.nodes:
        if node.stmt is not None:
            by_stmt.setdefault(node.stmt.nid, []).append(node)
    out = []
    for stmt in _statements(ctx.node.body):
        if not isinstance(stmt, n.Case) or not isinstance(stmt.selector, n.Name):
            continue
        var = ctx.facts.variable_of(stmt.selector)
        if var is None or var.section not in (LOCAL, OUTPUT) or not isinstance(var.type, (t.IntType, t.EnumType)):
            continue
        case_node = next(node for node in by_stmt[stmt.nid] if node.kind == "case")
        machine = Machine(var, stmt, case_node, set())
        for labels, body in stmt.elements:
            values = _label_values(ctx, labels)
            for inner in _statements(body):
                for node in by_stmt.get(inner.nid, []):
                    machine.inside.add(node.index)
                    machine.branch_of.setdefault(node.index, values)
                    if node.kind == "assign" and place_key(inner.target, ctx.facts) == var.key:
                        target = ctx.facts.const(inner.value)
                        for v in values:
                            dest = machine.transitions.setdefault(v, set())
                            if isinstance(target, int):
                                dest.add(target)
                            else:
                                offset = _offset(inner.value, var.key, ctx)
                                if offset is not None:
                                    dest.add(v + offset)
        if any(machine.transitions.values()):
            out.append(machine)
    return out


def _offset(value: n.Expr, key: str, ctx: PouContext) -> int | None:
    """`S + c` / `S - c` → c."""
    if isinstance(value, n.Binary) and value.op in ("PLUS", "MINUS") and place_key(value.left, ctx.facts) == key:
        c = ctx.facts.const(value.right)
        if isinstance(c, int) and not isinstance(c, bool):
            return c if value.op == "PLUS" else -c
    return None


def _initial_state_value(var, ctx: PouContext) -> int | None:
    if isinstance(var.init, int):
        return var.init
    if isinstance(var.type, t.EnumType):
        return var.type.default if var.type.default is not None else (var.type.members[0][1] if var.type.members else None)
    return 0


def identifier_words(name: str) -> list[str]:
    """`ToError_Sts` → ['to', 'error', 'sts']; `xDone` → ['x', 'done']; `bERR` → ['b', 'err']."""
    import re
    return [w.lower() for w in re.findall(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|\d+", name)]


def _is_exit_name(name: str) -> bool:
    """An error or done flag by its name: a word of it is Error/Err or Done (PLCopen outputs and the
    usual `ToError_Sts`, `bErr`, `xDone`); `Abandoned` or `Errand` are not."""
    return any(w in ("error", "err", "done") for w in identifier_words(name))


def exit_nodes(ctx: PouContext, machine: Machine, others: list[Machine] = ()) -> dict[int, n.Span]:
    """Nodes that end the sequence: `X := TRUE` on an error/done BOOL the machine never reads,
    in its own steps or in the statements around it (not inside another step machine, whose
    own steps run in whatever step this one is in)."""
    elsewhere = set()
    for other in others:
        if other is not machine:
            elsewhere |= other.inside - machine.inside
    read_inside: set[str] = set()
    for node in ctx.cfg.nodes:
        if node.index in machine.inside or node is machine.case_node:
            for access in node_accesses(node, ctx.facts):
                if access.kind == "read":
                    read_inside.add(access.var.key)
    out = {}
    for node, state in ctx.reachable_nodes():
        if node.kind != "assign" or node.index in elsewhere:
            continue
        target = node.stmt.target
        key = place_key(target, ctx.facts)
        name = target.name if isinstance(target, n.Member) else (target.parts[-1] if isinstance(target, n.Name) else "")
        if key is None or not isinstance(ctx.type_of(target), t.BoolType) or not _is_exit_name(name):
            continue
        root = key.split(".", 1)[0]
        if root in read_inside:
            continue
        value = ctx.value(node.stmt.value, state)
        if value == (1, 1):
            out[node.index] = node.stmt.span
    return out


@dataclass(frozen=True)
class Resource:
    """What is held: `acquire_nodes`/`release_nodes` are CFG node indices; `acquire_edges`/
    `release_edges` are ids of condition edges (e.g. the TRUE edge of `IF connect.Done`)."""

    what: str
    acquire_nodes: frozenset
    release_nodes: frozenset
    acquire_edges: frozenset = frozenset()
    release_edges: frozenset = frozenset()
    acquire_line: int = 0


@dataclass
class Leak:
    node_index: int
    span: n.Span
    states: set = field(default_factory=set)     # steps in which the error path runs


class _Typestate:
    def __init__(self, ctx: PouContext, machine: Machine, resources: list[Resource],
                 exits: dict[int, n.Span]) -> None:
        self.ctx = ctx
        self.machine = machine
        self.exits = exits
        # per node / edge: the resources it acquires and releases (indices into `resources`)
        self.acquire_at: dict[int, frozenset] = {}
        self.release_at: dict[int, frozenset] = {}
        self.acquire_on: dict[int, frozenset] = {}
        self.release_on: dict[int, frozenset] = {}
        for index, r in enumerate(resources):
            for table, keys in ((self.acquire_at, r.acquire_nodes), (self.release_at, r.release_nodes),
                                (self.acquire_on, r.acquire_edges), (self.release_on, r.release_edges)):
                for key in keys:
                    table[key] = table.get(key, frozenset()) | {index}
        self.feasible = ctx.feasible_edges
        self.assigns: dict[int, object] = {}
        for node in ctx.cfg.nodes:
            if node.kind == "assign" and place_key(node.stmt.target, ctx.facts) == machine.key:
                value = ctx.facts.const(node.stmt.value)
                if isinstance(value, int) and not isinstance(value, bool):
                    self.assigns[node.index] = ("set", value)
                elif _offset(node.stmt.value, machine.key, ctx) is not None:
                    self.assigns[node.index] = ("add", _offset(node.stmt.value, machine.key, ctx))
                else:
                    state = ctx.state_at(node)
                    rng = ctx.value(node.stmt.value, state) if state is not None else None
                    self.assigns[node.index] = ("set", rng[0]) if is_point(rng) else ("set", None)
        self.calls: dict[int, set[str]] = {}
        for node in ctx.cfg.nodes:
            keys = set()
            for call in node_calls(node):
                info = ctx.facts.call(call)
                if info is not None and info.is_fb and info.instance is not None:
                    key = place_key(info.instance, ctx.facts)
                    if key is not None:
                        keys.add(key)
            if keys:
                self.calls[node.index] = keys
        self.active = (set(self.acquire_at) | set(self.release_at) | set(self.exits) | set(self.assigns)
                       | set(self.calls))
        self.positives: dict[int, frozenset] = {}

    def initial(self):
        return frozenset({(_initial_state_value(self.machine.var, self.ctx), frozenset(), None, False, frozenset())})

    def next_call(self, exit_state):
        # A sequence that ended with an error while holding the resource has been reported
        # (`leaks`); carrying `held` into the next run would report every later error again.
        return frozenset((s, held if err is None or moved else frozenset(), None, False, frozenset())
                         for s, held, err, moved, _a in exit_state)

    def transfer(self, node, state):
        i = node.index
        if i not in self.active:
            return state
        acquire = self.acquire_at.get(i, frozenset())
        release = self.release_at.get(i, frozenset())
        out = set()
        for s, held, err, moved, assumed in state:
            if i in self.calls:
                assumed = frozenset(a for a in assumed if a.rsplit(".", 1)[0] not in self.calls[i])
            if acquire or release:
                held = (held - release) | acquire
            if i in self.exits:
                steps = self.machine.branch_of.get(i) or ((s,) if s is not None else ())
                err, moved = (i, steps), False
            if i in self.assigns:
                how, value = self.assigns[i]
                s = value if how == "set" else (s + value if s is not None else None)
                if err is not None:
                    moved = True
                if i not in self.machine.inside:
                    # a (re)start from outside the steps: the previous run ended, through an exit
                    # that has been checked; correlating with the state diagram that guards the
                    # restart is beyond a per-variable analysis
                    held = frozenset()
            out.add((s, held, err, moved, assumed))
        return frozenset(out)

    def edge(self, edge, state):
        if id(edge) not in self.feasible:
            return None
        label = edge.label
        if label is None:
            return state
        out = set()
        if edge.src is self.machine.case_node and label[0] in ("case", "else"):
            values = _label_values(self.ctx, label[1])
            for s, held, err, moved, assumed in state:
                if label[0] == "case":
                    if s is None:
                        out.add((values[0] if len(values) == 1 else None, held, err, moved, assumed))
                    elif s in values:
                        out.add((s, held, err, moved, assumed))
                elif s is None or s not in values:
                    out.add((s, held, err, moved, assumed))
            return frozenset(out) or None
        if label[0] == "true":
            positives = self.positives.get(id(edge))
            if positives is None:
                positives = self.positives[id(edge)] = positive_members(label[1], self.ctx)
            if not positives and id(edge) not in self.acquire_on and id(edge) not in self.release_on:
                return state
            for tup in state:
                s, held, err, moved, assumed = tup
                blocked = False
                for key in positives:
                    base, pin = key.rsplit(".", 1)
                    if any(a.rsplit(".", 1)[0] == base and a != key for a in assumed):
                        blocked = True
                if blocked:
                    continue
                assumed = assumed | positives
                acquire = self.acquire_on.get(id(edge))
                release = self.release_on.get(id(edge))
                if acquire or release:
                    held = (held - (release or frozenset())) | (acquire or frozenset())
                out.add((s, held, err, moved, assumed))
            return frozenset(out) or None
        return state

    def join(self, a, b):
        return a | b

    def widen(self, old, new, rounds=1, at=None):
        return new

    def leq(self, a, b):
        return a <= b


def positive_members(cond: n.Expr, ctx: PouContext, positive: bool = True) -> frozenset:
    """PLCopen outputs (`inst.done`, …) a condition requires TRUE on its TRUE edge."""
    if isinstance(cond, n.Member) and positive and cond.name.lower() in _EXCLUSIVE \
            and isinstance(ctx.type_of(cond.base), t.FBType):
        key = place_key(cond, ctx.facts)
        return frozenset({key}) if key is not None else frozenset()
    if isinstance(cond, n.Unary) and cond.op == "NOT":
        return frozenset()
    if isinstance(cond, n.Binary) and cond.op in ("AND", "AMP"):
        return positive_members(cond.left, ctx) | positive_members(cond.right, ctx)
    return frozenset()


def release_reachable(machine: Machine, resource: Resource) -> set[int]:
    direct = {v for i in resource.release_nodes for v in machine.branch_of.get(i, ())}
    reach = set(direct)
    changed = True
    while changed:
        changed = False
        for state, targets in machine.transitions.items():
            if state not in reach and targets & reach:
                reach.add(state)
                changed = True
    return reach


def acquired_in(ctx: PouContext, machine: Machine, resource: Resource) -> bool:
    """Does the machine's own steps acquire the resource? (Only that machine is checked.)"""
    if resource.acquire_nodes & machine.inside:
        return True
    for node in ctx.cfg.nodes:
        if node.index in machine.inside and any(id(e) in resource.acquire_edges for e in node.succs):
            return True
    return False


def leaks(ctx: PouContext, machine: Machine, resources: list[Resource],
          machines: list[Machine] = ()) -> dict[int, list[Leak]]:
    """Leaks of each resource the machine's own steps acquire: resource index → leaks.
    One typestate solve covers all the resources of a machine."""
    chosen = [i for i, r in enumerate(resources) if acquired_in(ctx, machine, r)]
    if not chosen:
        return {}
    exits = exit_nodes(ctx, machine, machines)
    if not exits:
        return {}
    analysis = _Typestate(ctx, machine, [resources[i] for i in chosen], exits)
    solution = solve(ctx.cfg, analysis)
    at_exit = solution.at(ctx.cfg.exit)
    if not at_exit:
        return {}
    ok_states = [release_reachable(machine, resources[i]) for i in chosen]
    found: list[dict[int, Leak]] = [{} for _ in chosen]
    for s, held, err, moved, _assumed in at_exit:
        if err is None:
            continue
        index, steps = err
        for local in held:
            if moved and s is not None and s in ok_states[local]:
                continue
            leak = found[local].setdefault(index, Leak(index, exits[index]))
            leak.states.update(v for v in steps if v is not None)
    return {chosen[local]: sorted(f.values(), key=lambda lk: (lk.span.line, lk.span.column))
            for local, f in enumerate(found) if f}


def nonlocal_flags(ctx: PouContext, machine: Machine) -> dict[str, list]:
    """BOOL places outside the FB (outputs, in-outs, globals) that the machine's branches set
    TRUE: place key → [CFG nodes assigning it]."""
    sections = {key: var.section for key, var in ctx.info.variables.items()}
    candidates: dict[str, list] = {}
    for node in ctx.cfg.nodes:
        if node.kind != "assign":
            continue
        target = node.stmt.target
        key = place_key(target, ctx.facts)
        if key is None or not isinstance(ctx.type_of(target), t.BoolType):
            continue
        root = key.split(".", 1)[0].split("[", 1)[0]
        if sections.get(root, GLOBAL) not in (OUTPUT, IN_OUT, EXTERNAL, GLOBAL):
            continue
        name = target.name if isinstance(target, n.Member) else target.parts[-1] if isinstance(target, n.Name) else ""
        if _is_exit_name(name):
            continue
        candidates.setdefault(key, []).append(node)
    out = {}
    for key, nodes in candidates.items():
        sets_inside = False
        for node in nodes:
            state = ctx.state_at(node)
            if state is not None and node.index in machine.inside \
                    and ctx.value(node.stmt.value, state) == (1, 1):
                sets_inside = True
        if sets_inside:
            out[key] = nodes
    return out
