"""Watched variables: glob patterns over variable paths, and a fast per-scan sampler.

A *path* names one variable the way `vm.get` does: a global (`Cobot.Connected`), a program
variable (`PnP_Example_Instance.Prg_Step`), an FB member (`PnP_Example_Instance.Timer_1.Q`), a
struct field or an array element (`PnP_MoveParameters[2].TargetPosition.Z`). Only elementary
values (the leaves) are recorded; a pattern naming a struct, FB or array records every leaf in it.

Pattern syntax (case-insensitive, like ST names):

=========  ===============================================================================
``*``      any characters within one name or index: ``Cobot.*``, ``PnP_MoveParameters[*].Speed``
``**``     any characters across levels: ``PnP_Example_Instance.**.Busy``
``?``      one character of a name
``[``      literal: ``[`` and ``]`` are the index brackets (``Data[1*]`` = indices 1, 10..19, 1xx)
=========  ===============================================================================

A pattern without a wildcard is resolved exactly as `vm.resolve` does, so it may also name
VAR_IN_OUT and VAR_EXTERNAL members (which globs skip: they alias the variable they refer to).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Callable

from stvm.lower.layout import is_storage_name
from stvm.runtime.catalog import Catalog, listed_slots
from stvm.semantics import types as t


class WatchError(ValueError):
    """A watch pattern that matches nothing or a path that does not resolve."""


@dataclass(frozen=True)
class Signal:
    """One recorded leaf: its path, type, and how to reach it from a root object.

    `root` is a program instance or the globals object; `steps` the storage names (the layout's) and
    list indices that lead from it to the value. Walking the steps each scan (instead of keeping
    the final container) stays right when an array of structs is assigned as a whole (the element
    objects are replaced by copies).
    """

    name: str
    type: t.Type
    root: Any
    steps: tuple[str | int, ...]

    @property
    def kind(self) -> str:
        """bool, int, real, time, string or enum (the recordable kinds)."""
        return self.type.kind


def type_text(ty: t.Type) -> str:
    if t.is_wide(ty):
        return ty.name   # WSTRING, WSTRING[n]
    if isinstance(ty, t.StringType):
        return f"STRING[{ty.size}]" if ty.size != 1986 else "STRING"
    if isinstance(ty, t.EnumType):
        return ty.qualname or ty.name
    return ty.name


def compile_pattern(pattern: str) -> re.Pattern[str]:
    """The regular expression of a watch pattern (syntax in the module docstring)."""
    out = []
    i = 0
    while i < len(pattern):
        ch = pattern[i]
        if pattern.startswith("**", i):
            out.append(".*")
            i += 2
            continue
        if ch == "*":
            out.append(r"[^.\[\]]*")
        elif ch == "?":
            out.append(r"[^.\[\]]")
        else:
            out.append(re.escape(ch))
        i += 1
    return re.compile("".join(out), re.IGNORECASE)


_ELEMENTARY = ("bool", "int", "real", "time", "string", "enum")


def select_signals(vm, patterns: list[str]) -> list[Signal]:
    """The leaves the patterns name, in pattern order then declaration order, without repeats.

    Raises WatchError for a pattern that matches nothing (with close names as a hint).
    """
    catalog = Catalog(vm)   # the one list of variables (stvm.runtime.catalog): order, skip rules, paths
    nodes = None
    chosen: dict[str, Signal] = {}
    for pattern in patterns:
        pattern = pattern.strip()
        if not pattern:
            continue
        found: list[Signal] = []
        if not any(ch in pattern for ch in "*?"):
            found = _exact(vm, catalog, pattern)
        else:
            if nodes is None:   # a program instance itself is not a variable
                nodes = [(node.path, node.type, node.root, node.steps) for node in catalog.walk()
                         if node.kind != "program"]
            regex = compile_pattern(pattern)
            matched_prefixes: list[str] = []
            for name, ty, root, steps in nodes:
                lowered = name.lower()
                inside = any(lowered.startswith(p) for p in matched_prefixes)
                if not inside and regex.fullmatch(name):
                    if ty.kind not in _ELEMENTARY:
                        matched_prefixes.append(lowered + ".")
                        matched_prefixes.append(lowered + "[")
                        continue
                    inside = True
                if inside and ty.kind in _ELEMENTARY:
                    found.append(Signal(name, ty, root, steps))
        if not found:
            raise WatchError(f"--watch {pattern!r} matches no variable{_hint(vm, pattern)}")
        for signal in found:
            chosen.setdefault(signal.name.lower(), signal)
    return list(chosen.values())


def _exact(vm, catalog: Catalog, path: str) -> list[Signal]:
    from stvm.runtime.vm import PathError   # lazy: start-up
    try:
        container, key, ty = vm.resolve(path)
    except PathError as exc:
        raise WatchError(f"--watch {path!r}: {exc}{_hint(vm, path)}") from exc
    # a path the catalog lists takes its spelling and its route from there; one through a
    # VAR_IN_OUT is not listed: its leaves are read from the container the path resolves to
    node = catalog.node(path) or catalog.detached(re.sub(r"\s+", "", path), ty, container, (key,))
    return [Signal(leaf.path, leaf.type, leaf.root, leaf.steps) for leaf in node.walk()
            if leaf.type.kind in _ELEMENTARY]


def _hint(vm, pattern: str) -> str:
    """` (did you mean …?)` for a pattern that matches nothing: the names are followed as far
    as they resolve, and the first one that does not is compared with the members there, so
    `Cobot.Conected` suggests `Cobot.Connected`, not `Cobot`."""
    import difflib
    parts = re.split(r"\.", re.sub(r"\s+", "", pattern))
    if any(ch in pattern for ch in "[*?^"):
        parts = re.split(r"\.", re.split(r"[\[*?^]", re.sub(r"\s+", "", pattern), maxsplit=1)[0])
    heads = {var.name.lower(): ("global", var.name) for var in vm.model.globals.values()}
    heads.update({n.lower(): ("instance", n) for n, _, _ in vm.instances.values()})
    close = difflib.get_close_matches(parts[0], [name for _, name in heads.values()], n=3, cutoff=0.6)
    found = heads.get(parts[0].lower())
    if found is None or len(parts) == 1:
        return f" (did you mean {', '.join(close)}?)" if close else ""
    layout = _layout_of_head(vm, found)
    prefix = found[1]
    for part in parts[1:]:
        if layout is None:
            return ""
        members = {slot.name.lower(): slot for slot in listed_slots(layout)}
        slot = members.get(part.lower())
        if slot is None:
            close = difflib.get_close_matches(part, [m.name for m in members.values()], n=3, cutoff=0.6)
            if not close:
                close = [m.name for m in members.values() if m.name.lower().startswith(part.lower()[:3])][:3]
            return f" (did you mean {', '.join(f'{prefix}.{c}' for c in close)}?)" if close else ""
        prefix = f"{prefix}.{slot.name}"
        layout = vm.layouts.of(slot.type)
    return ""


def _layout_of_head(vm, found: tuple[str, str]):
    kind, name = found
    if kind == "instance":
        for inst_name, _inst, qualname in vm.instances.values():
            if inst_name == name:
                return vm.layouts.pous[qualname.lower()]
        return None
    slot = vm.layouts.globals.slot(name)
    return vm.layouts.of(slot.type) if slot is not None else None


def _expression(root_name: str, steps: tuple) -> str:
    parts = [root_name]
    for step in steps:
        if isinstance(step, int):
            parts.append(f"[{int(step)}]")
        elif is_storage_name(step):
            parts.append("." + step)
        else:  # resolved containers may hand us a mangled key we did not make: stvm bug if so
            raise AssertionError(f"unsafe attribute {step!r}")
    return "".join(parts)


@dataclass(frozen=True)
class CompiledReads:
    """The generated text that reads `signals` from their roots (`compile_reads`)."""

    roots: list[Any]          # the root objects, bound as default arguments r0, r1, … of the function
    prelude: list[str]        # `        p0 = r0.v_cobot`: each prefix shared by several signals, once
    expressions: list[str]    # one expression per signal, through the prelude's locals


def compile_reads(signals: list[Signal]) -> CompiledReads:
    """The text of one attribute or item access per step, shared prefixes read once into locals.
    Only validated storage names (`is_storage_name`) and integer indices go into it."""
    roots: list[Any] = []
    root_ids: dict[int, int] = {}
    paths: list[tuple] = []
    for signal in signals:
        index = root_ids.get(id(signal.root))
        if index is None:
            index = root_ids[id(signal.root)] = len(roots)
            roots.append(signal.root)
        paths.append((index,) + tuple(signal.steps))
    uses: dict[tuple, int] = {}
    for path in paths:
        for k in range(2, len(path)):        # proper prefixes with at least one step
            uses[path[:k]] = uses.get(path[:k], 0) + 1
    shared = sorted((prefix for prefix, count in uses.items() if count > 1), key=len)
    local_of: dict[tuple, str] = {}
    prelude = []

    def expression(path: tuple) -> str:
        for k in range(len(path) - 1, 1, -1):
            name = local_of.get(path[:k])
            if name is not None:
                return _expression(name, path[k:])
        return _expression(f"r{path[0]}", path[1:])

    for prefix in shared:
        name = f"p{len(local_of)}"
        prelude.append(f"        {name} = {expression(prefix)}")
        local_of[prefix] = name
    return CompiledReads(roots, prelude, [expression(path) for path in paths])


def build_reader(reads: CompiledReads, name: str, args: str, returned: str, filename: str) -> Callable:
    """`def name(args, r0=r0, …)` running the prelude and returning `returned`, compiled once."""
    roots = reads.roots
    params = "".join(f", r{i}=r{i}" for i in range(len(roots)))
    params = (args + params) if args else params[2:]
    source = (f"def make({', '.join(f'r{i}' for i in range(len(roots)))}):\n"
              f"    def {name}({params}):\n" + "".join(line + "\n" for line in reads.prelude) +
              f"        return {returned}\n    return {name}\n")
    namespace: dict[str, Any] = {}
    exec(compile(source, filename, "exec"), namespace)
    return namespace["make"](*roots)


def make_sampler(signals: list[Signal]) -> Callable[[], tuple]:
    """A compiled function returning the current values of `signals` as one tuple.

    Generated code (`p0 = r0.v_cobot; return (p0.v_connected, p0.v_socket.v_handle, …)`) costs
    one attribute or item access per step, shared prefixes once per call, and no interpretation;
    only validated storage names (`is_storage_name`) and integer indices go into it. Every call walks from the roots
    again, so replaced objects (an array of structs assigned as a whole) are never stale.
    """
    reads = compile_reads(signals)
    exprs = reads.expressions
    result = "(" + ", ".join(exprs) + ("," if len(exprs) == 1 else "") + ")"
    return build_reader(reads, "sample", "", result, "<stvm-trace-sampler>")
