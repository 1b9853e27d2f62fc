"""Per-POU analysis context shared by the rules: the CFG and the range solution are built
once, on first use, whatever number of rules ask for them."""

from __future__ import annotations

from functools import cached_property

from stvm.lint.cfg import CFG, Node, build_cfg
from stvm.lint.facts_view import FactsView
from stvm.lint.intervals import Interval, RangeAnalysis, State, analyze_ranges
from stvm.lint.findings import Finding
from stvm.semantics import types as t
from stvm.syntax import nodes as n
from stvm.lint.dataflow import solve
from stvm.source import is_stdlib_file


class ProjectContext:
    """What every POU context shares: the checked project and the settings."""

    def __init__(self, analysis, settings) -> None:
        self.analysis = analysis
        self.facts = FactsView(analysis)
        self.settings = settings
        self.alias_ranges = _alias_subranges(analysis.units)

    def pou_contexts(self, include_stdlib: bool = False) -> list["PouContext"]:
        out = []
        for key, node in self.analysis.pou_nodes.items():
            info = self.analysis.model.pous.get(key)
            if info is None or info.native or not node.body:
                continue
            if is_stdlib_file(node.span.file) and not include_stdlib:
                continue
            out.append(PouContext(self, node, info))
        for key, node in self.analysis.pou_nodes.items():
            info = self.analysis.model.pous.get(key)
            if info is None or info.kind not in ("FUNCTION_BLOCK", "PROGRAM"):
                continue
            if is_stdlib_file(node.span.file) and not include_stdlib:
                continue
            out += self.method_contexts(node, info)
        return out

    def method_contexts(self, node: n.POU, info) -> list["PouContext"]:
        """The FB's METHODs and property accessors, linted like FUNCTIONs (their variables are
        fresh on every call; the instance's variables they use are not tracked)."""
        methods = getattr(self.analysis, "method_nodes", {})
        members = list(info.methods.values())
        for prop in info.properties.values():
            members += [m for m in (prop.getter, prop.setter) if m is not None]
        out = []
        for method in members:
            mnode = methods.get(method.key)
            if mnode is None or method.abstract or not mnode.body:
                continue
            sp = mnode.span
            word = "END_METHOD" if method.key.rsplit(".", 1)[-1].startswith(method.name.lower()) else "END_GET"
            end = n.Span(sp.file, sp.end_line, max(1, sp.end_column - len(word)), sp.end_line, sp.end_column)
            view = n.POU("FUNCTION", method.name, node.namespace, mnode.return_type, mnode.var_blocks, mnode.body,
                         mnode.pragmas, sp, end)
            as_function = method.replace(kind="FUNCTION", return_type=method.return_type or t.VOID)
            ctx = PouContext(self, view, as_function)
            ctx.method_of = info.name
            out.append(ctx)
        return out


class PouContext:
    def __init__(self, project: ProjectContext, node: n.POU, info) -> None:
        self.project = project
        self.node = node
        self.info = info
        self.facts = project.facts
        self.settings = project.settings
        self.method_of = ""       # a METHOD / property accessor (linted like a FUNCTION): its FB's name

    @cached_property
    def cfg(self) -> CFG:
        return build_cfg(self.node)

    @cached_property
    def oo_shared(self) -> bool:
        """An FB/PROGRAM whose variables its METHODs or PROPERTYs (or a base's) also read and write,
        or that inherits variables: its body alone does not show every access (the rules that
        need all of them skip it)."""
        pous = self.project.analysis.model.pous
        cur = self.info
        while cur is not None:
            if getattr(cur, "methods", None) or getattr(cur, "properties", None) or getattr(cur, "base", None):
                return True
            cur = pous.get(cur.base) if getattr(cur, "base", None) else None
        return False

    @cached_property
    def _ranges(self):
        return analyze_ranges(self.cfg, self.info, self.facts, self.settings, self.project.alias_ranges)

    @property
    def ranges(self) -> RangeAnalysis:
        return self._ranges[0]

    def state_at(self, node: Node) -> State | None:
        """The range state before `node` (None: the node is unreachable)."""
        return self._ranges[1].at(node)

    def value(self, expr: n.Expr, state: State) -> Interval | None:
        return self.ranges.ev.eval(expr, state)

    def reachable_nodes(self):
        for node in self.cfg.nodes:
            state = self.state_at(node)
            if state is not None:
                yield node, state

    @property
    def feasible_edges(self) -> set[int]:
        """ids of the CFG edges some execution can take (per the range analysis)."""
        return self._ranges[1].feasible

    def finding(self, code: str, message: str, span: n.Span) -> Finding:
        return Finding(code, message, span)

    def variable(self, name: str):
        return self.info.variables.get(name.lower())

    @property
    def is_fb(self) -> bool:
        return self.info.kind == "FUNCTION_BLOCK"

    def type_of(self, expr: n.Expr) -> t.Type | None:
        return self.facts.type_of(expr)


def _alias_subranges(units) -> dict[str, Interval]:
    """`TYPE Percent : INT(0..100); END_TYPE` → {'percent': (0, 100), 'ns\\percent': …}."""
    out: dict[str, Interval] = {}
    for unit in units:
        for decl in unit.types:
            body = decl.body
            if isinstance(body, n.AliasDecl) and isinstance(body.type_spec, n.SubrangeTypeSpec):
                rng = (body.type_spec.low, body.type_spec.high)
                out[decl.name.lower()] = rng
                out["\\".join(decl.namespace + (decl.name,)).lower()] = rng
    return out


class _SetAnalysis:
    """A may (union) or must (intersection) analysis over sets, on the feasible edges only."""

    def __init__(self, ctx: PouContext, initial: frozenset, transfer, must: bool, scan_reset: bool = True) -> None:
        self.ctx = ctx
        self._initial = initial
        self._transfer = transfer
        self.must = must

    def initial(self):
        return self._initial

    def next_call(self, exit_state):
        return self._initial

    def transfer(self, node, state):
        return self._transfer(node, state)

    def edge(self, edge, state):
        return state if id(edge) in self.ctx.feasible_edges else None

    def join(self, a, b):
        return a & b if self.must else a | b

    def widen(self, old, new, rounds=1, at=None):
        return new

    def leq(self, a, b):
        return a >= b if self.must else a <= b


def solve_sets(ctx: PouContext, initial: frozenset, transfer, must: bool):
    """Solve a set analysis for one call of the POU (no state carried between scans)."""
    return solve(ctx.cfg, _SetAnalysis(ctx, initial, transfer, must), scan_loop=False)
