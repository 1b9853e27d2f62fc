"""Pass 5 of the checker, after every body: whole-program rules (docs/architecture.md, "Checker
passes").

`ProgramChecks` needs the call facts the body checks recorded: how deep FB instances nest and calls
chain (E028), a FUNCTION_BLOCK or STRUCT containing itself, recursion of POUs and methods, and the
CONFIGURATION's tasks.
"""

from __future__ import annotations

from typing import Mapping

from stvm.semantics import types as t
from stvm.semantics.context import CheckContext, Pass
from stvm.semantics.model import (EXTERNAL, IN_OUT, TaskInfo)
from stvm.settings import Dialect
from stvm.source import is_stdlib_file
from stvm.syntax import nodes as n
from stvm.syntax.walk import calls_in


NESTING_LIMIT = 200
"""How deep FB instances may nest (a FB instance inside a FB instance inside …) and POU calls
may chain, for `stvm run` and `stvm debug` alike: deeper programs are a check-time error (E028)
naming the chain. Real PLC programs stay far below; 200 keeps the VM well inside Python's stack."""


def _aggregate_key(ty: t.Type) -> str | None:
    while isinstance(ty, t.ArrayType):
        ty = ty.element
    if isinstance(ty, (t.FBType, t.StructType)):
        return ty.qualname.lower()
    return None


def _longest_paths(graph: dict[str, list[tuple[str, str]]]) -> tuple[dict[str, int], dict[str, tuple[str, str] | None]]:
    """For each node: the number of nodes on the longest path starting there, and its first
    edge (label, successor). Iterative (no recursion); edges closing a cycle are ignored (cycles
    are reported by check_containment / check_recursion)."""
    depth: dict[str, int] = {}
    best: dict[str, tuple[str, str] | None] = {}
    for root in graph:
        if root in depth:
            continue
        stack = [(root, iter(graph.get(root, ())))]
        on_path = {root}
        while stack:
            key, edges = stack[-1]
            for _, succ in edges:
                if succ not in depth and succ not in on_path:
                    on_path.add(succ)
                    stack.append((succ, iter(graph.get(succ, ()))))
                    break
            else:
                stack.pop()
                on_path.discard(key)
                length, first = 1, None
                for label, succ in graph.get(key, ()):
                    if succ in depth and depth[succ] + 1 > length:
                        length, first = depth[succ] + 1, (label, succ)
                depth[key] = length
                best[key] = first
    return depth, best


def _cycles_closed(graph: Mapping[str, set[str]]) -> list[list[str]]:
    """The cycles a depth-first walk of a call graph closes (roots in the graph's order, callees
    sorted), each as the chain from the key called again back to it: `['a', 'b', 'a']`.

    Iterative: a nested function that calls itself is a reference cycle, which would keep
    whatever it closes over (the checker) alive until the collector runs."""
    state: dict[str, str] = {}
    cycles: list[list[str]] = []
    for root in graph:
        if root in state:
            continue
        state[root] = "open"
        chain = [root]
        stack = [iter(sorted(graph.get(root, ())))]
        while stack:
            for callee in stack[-1]:
                seen = state.get(callee)
                if seen == "open":
                    cycles.append(chain[chain.index(callee):] + [callee])
                elif seen is None:
                    state[callee] = "open"
                    chain.append(callee)
                    stack.append(iter(sorted(graph.get(callee, ()))))
                    break
            else:
                state[chain.pop()] = "done"
                stack.pop()
    return cycles


class ProgramChecks(Pass):
    """The checks that need every body checked (module docstring)."""

    def __init__(self, ctx: CheckContext, indexer, constants, oo) -> None:
        super().__init__(ctx)
        self.indexer = indexer       # index.Indexer
        self.constants = constants   # constants.ConstantEvaluator
        self.oo = oo                 # oo.ClassHierarchy

    def check_containment(self) -> None:
        """A FUNCTION_BLOCK or STRUCT may not contain itself, directly or through other members:
        its instance would be infinitely large."""
        state: dict[str, str] = {}   # key -> 'open' | 'done'

        def members(key: str) -> list[tuple[str, t.Type]]:
            if key in self.ctx.pous:
                return [(v.name, v.type) for v in self.ctx.pous[key].variables.values()
                        if v.section not in (IN_OUT, EXTERNAL)]
            decl = self.ctx.index.type_decls.get(key)
            if decl is not None and isinstance(decl.body, n.StructDecl):
                return [(name, t.StructType(fkey, fkey)) for name, fkey in self._struct_members(key, decl)]
            return []

        def key_of(ty: t.Type) -> str | None:
            while isinstance(ty, t.ArrayType):
                ty = ty.element
            if isinstance(ty, (t.FBType, t.StructType)):
                return ty.qualname.lower()
            return None

        reported: set[str] = set()

        def display(key: str) -> str:
            if key in self.ctx.pous:
                return self.ctx.pous[key].name
            decl = self.ctx.index.type_decls.get(key)
            return decl.name if decl is not None else key

        def span_of(key: str) -> n.Span:
            if key in self.ctx.pous:
                return self.ctx.pous[key].span
            return self.ctx.index.type_decls[key].span

        def visit(key: str, keys: list[str], names: list[str]) -> None:
            if state.get(key) == "done":
                return
            if state.get(key) == "open":
                start = keys.index(key)
                if key not in reported:
                    reported.add(key)
                    self.error(f"'{display(key)}' contains itself (through {'.'.join(names[start:])}): "
                               f"an instance would be infinitely large", span_of(key), "E026")
                return
            state[key] = "open"
            for name, ty in members(key):
                inner = key_of(ty)
                if inner is not None:
                    visit(inner, keys + [key], names + [name])
            state[key] = "done"

        for key, pou in self.ctx.pous.items():
            if pou.kind != "FUNCTION":
                visit(key, [], [])
        for key, decl in self.ctx.index.type_decls.items():
            if isinstance(decl.body, n.StructDecl):
                visit(key, [], [])
        del visit   # a closure calling itself is a cycle: it would keep the checker alive

    def check_nesting_depth(self) -> bool:
        """FB instances nested in FB instances (or structs), and POUs calling POUs, at most
        NESTING_LIMIT deep: the same limit for `stvm run` and `stvm debug` (the VM builds and
        calls them on the Python stack). Returns False if a chain is too deep."""
        contains: dict[str, list[tuple[str, str]]] = {}
        for key, pou in self.ctx.pous.items():
            if pou.kind != "FUNCTION":
                contains[key] = [(v.name, inner) for v in pou.variables.values()
                                 if v.section not in (IN_OUT, EXTERNAL)
                                 for inner in [_aggregate_key(v.type)] if inner is not None]
        for key, decl in self.ctx.index.type_decls.items():
            if isinstance(decl.body, n.StructDecl):
                contains[key] = [(name, inner) for name, inner in self._struct_members(key, decl)]
        calls: dict[str, list[tuple[str, str]]] = {key: [] for key in self.ctx.index.pou_nodes}
        for key, node in self.ctx.index.pou_nodes.items():
            seen: set[str] = set()
            for call in self._calls_of(key, node):
                info = self.ctx.facts.calls.get(call.nid)
                if info is not None and info.pou.key not in seen:
                    seen.add(info.pou.key)
                    calls[key].append((info.pou.name, info.pou.key))
        ok = True
        reported: set[str] = set()
        for graph, what in ((contains, "instances"), (calls, "calls")):
            depth, best = _longest_paths(graph)
            deep = {key for key, d in depth.items() if d > NESTING_LIMIT}
            inside = {succ for key in deep for _, succ in graph.get(key, ()) if succ in deep}
            for root in sorted(deep - inside - reported):   # one error per chain
                reported.add(root)
                ok = False
                chain = [self._display(root)]
                key = root
                while best.get(key) is not None:
                    label, key = best[key]
                    chain.append(f".{label} ({self._display(key)})" if what == "instances" else self._display(key))
                shown = chain if len(chain) <= 8 else chain[:5] + ["…"] + chain[-2:]
                if what == "instances":
                    text = f"FB instances and structures nested {depth[root]} deep: {' '.join(shown)}"
                else:
                    text = f"calls nested {depth[root]} deep: {' -> '.join(shown)}"
                self.error(f"{text}; stvm's limit is {NESTING_LIMIT} levels (for run and debug alike)",
                           self._span_of_key(root), "E028")
        return ok

    def _calls_of(self, key: str, node) -> list[n.Call]:
        """Every Call in a POU's body, in `syntax.walk`'s order (one walk per POU,
        shared by the nesting and the recursion check)."""
        cache = self.__dict__.setdefault("_calls_cache", {})
        calls = cache.get(key)
        if calls is None:
            calls = cache[key] = calls_in(node.body)
        return calls

    def _struct_members(self, key: str, decl) -> list[tuple[str, str]]:
        out = []
        for fdecl in decl.body.fields:
            spec = fdecl.type_spec
            while isinstance(spec, n.ArrayTypeSpec):
                spec = spec.element
            if isinstance(spec, n.NamedTypeSpec):
                fkey = self.ctx.index.lookup_type_key(spec.parts, spec.rooted, decl.namespace) \
                    or self.ctx.index.lookup_pou_key(spec.parts, decl.namespace)
                if fkey is not None:
                    out += [(name, fkey) for name, _ in fdecl.names]
        return out

    def _display(self, key: str) -> str:
        if key in self.ctx.pous:
            return self.ctx.pous[key].name
        decl = self.ctx.index.type_decls.get(key)
        return decl.name if decl is not None else key

    def _span_of_key(self, key: str) -> n.Span:
        if key in self.ctx.pous:
            return self.ctx.pous[key].span
        return self.ctx.index.type_decls[key].span

    def check_recursion(self) -> None:
        """IEC 61131-3 (and Sysmac) forbid recursive calls of functions and FBs."""
        graph: dict[str, set[str]] = {key: set() for key in self.ctx.index.pou_nodes}
        for key, node in self.ctx.index.pou_nodes.items():
            for call in self._calls_of(key, node):
                info = self.ctx.facts.calls.get(call.nid)
                if info is not None and info.pou.kind == "FUNCTION":
                    graph[key].add(info.pou.key)
        for cycle in _cycles_closed(graph):
            names = " -> ".join(self.ctx.pous[k].name for k in cycle)
            node = self.ctx.index.pou_nodes[cycle[0]]
            self.error(f"recursive call {names}: IEC 61131-3 does not allow recursion", node.span, "E027")

    def check_method_recursion(self) -> None:
        """A METHOD (or property accessor) calling itself, directly or through other methods, by
        static resolution (`M()`, `THIS^.M()`, `fb.M()`, `SUPER^.M()`; a call through an interface
        is not followed). IEC 61131-3 forbids recursion (as for functions, check_recursion): an
        error under iec and sysmac. CODESYS and TwinCAT allow recursive methods (linked lists):
        a warning there, since a deep enough recursion ends in a stack-overflow fault."""
        graph: dict[str, set[str]] = {}
        for info in list(self.ctx.pous.values()):
            if info.kind not in ("FUNCTION_BLOCK", "PROGRAM") or info.native:
                continue
            for method in self.oo.members_of(info):
                node = self.ctx.method_nodes.get(method.key)
                if node is None:
                    continue
                calls = (self.ctx.facts.calls.get(call.nid) for call in self._calls_of(method.key, node))
                graph[method.key] = {call.pou.key for call in calls
                                     if call is not None and call.pou.kind == "METHOD" and call.oo != "itf"}
        if not any(graph.values()):
            return
        methods = {m.key: m for info in self.ctx.pous.values() for m in self.oo.members_of(info)}
        allowed = self.ctx.settings.dialect in (Dialect.CODESYS, Dialect.TWINCAT)

        def name(key: str) -> str:
            m = methods[key]
            return f"{self.ctx.pous[m.owner].name}.{m.name}" if m.owner in self.ctx.pous else m.name

        for cycle in _cycles_closed(graph):
            names = " -> ".join(name(k) for k in cycle)
            span = self.ctx.method_nodes[cycle[0]].name_span
            if allowed:
                self.warning(f"recursive method call {names}: allowed in {self.ctx.settings.dialect.value}, "
                             f"but a recursion too deep ends the run in a stack-overflow fault", span, "W002")
            else:
                self.error(f"recursive method call {names}: IEC 61131-3 does not allow recursion", span, "E027")

    def check_configuration(self) -> tuple[list[TaskInfo], list[str]]:
        configs = [c for u in self.ctx.units for c in u.configurations]
        if len(configs) > 1:
            self.error("more than one CONFIGURATION", configs[1].span, "E030")
        if configs:
            conf = configs[0]
            tasks: dict[str, TaskInfo] = {}
            for res in conf.resources:
                for task in res.tasks:
                    self.indexer.check_identifier(task.name, task.span)
                    params = {k: v for k, v in task.params}
                    interval = params.get("INTERVAL")
                    if interval is None:
                        self.error(f"task '{task.name}' needs INTERVAL (event tasks are not supported)", task.span, "E030")
                        continue
                    ns = self.constants.const_value(interval, (), None)
                    if not isinstance(ns, int) or isinstance(interval, n.IntLiteral) or ns <= 0:
                        self.error("INTERVAL must be a positive TIME literal", interval.span, "E030")
                        continue
                    prio = self.constants.const_value(params.get("PRIORITY", n.IntLiteral(0)), (), None)
                    if task.name.lower() in tasks:
                        self.error(f"duplicate task '{task.name}'", task.span, "E010")
                    tasks[task.name.lower()] = TaskInfo(task.name, ns, prio if isinstance(prio, int) else 0, [])
                for prog in res.programs:
                    self.indexer.check_identifier(prog.instance, prog.span)
                    key = self.ctx.index.lookup_pou_key(prog.type_name, ())
                    if key is None or self.ctx.pous[key].kind != "PROGRAM":
                        self.error(f"unknown program type '{chr(92).join(prog.type_name)}'", prog.span, "E032")
                        continue
                    if prog.task is None or prog.task.lower() not in tasks:
                        self.error(f"program '{prog.instance}' needs WITH <task> naming a declared task", prog.span, "E030")
                        continue
                    if any(p[0].lower() == prog.instance.lower() for tk in tasks.values() for p in tk.programs):
                        self.error(f"duplicate program instance '{prog.instance}'", prog.span, "E010")
                        continue
                    tasks[prog.task.lower()].programs.append((prog.instance, self.ctx.pous[key].qualname))
            ordered = sorted(tasks.values(), key=lambda tk: tk.priority)
            return ordered, []
        programs = [info.qualname for key, info in self.ctx.pous.items()
                    if info.kind == "PROGRAM" and not is_stdlib_file(info.file)]
        return [], programs
