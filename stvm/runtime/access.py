"""Variables of a running program by path, through the lowering's layout (`stvm.lower.layout`).

A path names one variable as ST would: a global (`Cobot.Connected`), a program variable
(`Main.Prg_Step`), an FB member (`Main.Timer_1.Q`), a struct field, an array element
(`Main.arr[3]`, `Main.grid[1, 2]`) or the target of a reference (`Main.r^`). `resolve` turns it into
(container, key, type): `container[key]` (an int key) or `getattr(container, key)` holds the value.

This is the one accessor the VM's `get`/`set`/`accessor`, and through them `--print`, `--set`,
`--until`, scenarios, the trace, the debugger, DAP, the HMI and OPC UA, are built on. Storage names
come only from the layout's slots; nothing here knows how lowering spells them.
"""

from __future__ import annotations

import functools
from typing import Any, Mapping

from stvm.lower.layout import ProjectLayout, VarSlot
from stvm.runtime import paths
from stvm.runtime.values import AttrRef, ItemRef, MapRef, OpenArray
from stvm.semantics import types as t


class PathError(KeyError):
    """A variable path (`Main.x`, `Main.fb.Q`, `Main.arr[2]`, a global) that does not resolve."""

    def __str__(self) -> str:
        return str(self.args[0])


class UnboundInOut(PathError):
    """The path is well-formed but goes through a VAR_IN_OUT the FB has not been called with yet."""


@functools.lru_cache(maxsize=4096)
def parse_path(path: str) -> tuple[tuple[str, str], ...]:
    """(kind, text) tokens of a path: ("name", "Q"), ("index", "1,2"), ("deref", "^"), read by
    the one strict path reader (stvm/runtime/paths.py: `Main..x` or `Main.x; DROP` is an error).

    Memoised (bounded): scenarios, the demo, the HMI and OPC UA read the same few paths every
    scan, and parsing one costs about as much as the rest of a `vm.get`."""
    try:
        return paths.parse_path(path)
    except paths.PathSyntaxError as exc:
        raise PathError(str(exc)) from None


class VariableAccess:
    """Path resolution over one VM's globals and program instances."""

    def __init__(self, layouts: ProjectLayout, globals_obj: Any,
                 instances: Mapping[str, tuple[str, Any, str]]) -> None:
        self.layouts = layouts
        self.globals = globals_obj
        self.instances = instances    # lower-case name → (name, instance, program qualname), live

    def resolve(self, path: str) -> tuple[Any, Any, t.Type]:
        tokens = parse_path(path)
        first, rest = tokens[0][1], tokens[1:]
        key = first.lower()
        if key in self.instances and rest and rest[0][0] == "name":
            _, inst, qualname = self.instances[key]
            layout = self.layouts.pous[qualname.lower()]
            name = rest[0][1]
            slot = layout.slots.get(name.lower())
            if slot is None:
                raise PathError(f"{first} has no variable {name!r}")
            if slot.section == "VAR_EXTERNAL":
                return self._walk(self.globals, self._global(slot.name).storage,
                                  self._global(slot.name).type, rest[1:], path)
            return self._walk(inst, slot.storage, slot.type, rest[1:], path)
        glob = self.layouts.globals.slot(first)
        if glob is not None:
            return self._walk(self.globals, glob.storage, glob.type, rest, path)
        if key in self.instances:
            raise PathError(f"{path!r} names a program instance; add a variable: {first}.<var>")
        raise PathError(f"unknown variable {path!r} (programs: {', '.join(n for n, _, _ in self.instances.values())})")

    def _global(self, name: str) -> VarSlot:
        slot = self.layouts.globals.slot(name)
        assert slot is not None, name   # the checker resolved every VAR_EXTERNAL to a global
        return slot

    def _walk(self, container: Any, key: Any, ty: t.Type, rest: list, path: str) -> tuple[Any, Any, t.Type]:
        for kind, text in rest:
            value = container[key] if isinstance(key, int) else getattr(container, key)
            if kind == "deref":
                # `r^`: through a REF_TO/POINTER TO/REFERENCE TO to the variable it refers to
                if not isinstance(ty, t.RefType) or ty.is_null:
                    raise PathError(f"{path!r}: '^' needs a reference, {ty.name} is not one")
                if value is None:
                    raise UnboundInOut(f"{path!r}: the reference is NULL")
                if isinstance(value, AttrRef):
                    container, key = value.obj, value.attr
                elif isinstance(value, ItemRef):
                    container, key = value.lst, value.index
                # an aggregate's reference is the aggregate itself: (container, key) stays
                ty = ty.target
                if isinstance(ty, t.StructType):   # (a self-referencing struct's placeholder)
                    ty = self.layouts.of(ty).type or ty
                continue
            if kind == "name":
                layout = self.layouts.of(ty)
                if layout is None:
                    raise PathError(f"{path!r}: {ty.name} has no members")
                slot = layout.slot(text)
                if slot is None:
                    raise PathError(f"{path!r}: {ty.name} has no member {text!r}")
                container, key, ty = value, slot.storage, slot.type
                if slot.section == "VAR_EXTERNAL":   # the instance has no storage of its own for it
                    container, key, ty = self.globals, self._global(slot.name).storage, self._global(slot.name).type
                elif slot.section == "VAR_IN_OUT":
                    container, key = _through_reference(container, key, path)
            else:
                if isinstance(ty, t.ArrayType) and ty.dims is None and isinstance(value, OpenArray):
                    # an ARRAY[*, *] parameter: the caller's lists, with the bounds it was given
                    ty = t.ArrayType(ty.name, ty.element, tuple(value.bounds))
                    container, key, value = value, "data", value.data
                if not isinstance(ty, t.ArrayType) or ty.dims is None:
                    raise PathError(f"{path!r}: not an array")
                try:
                    indices = [int(x.strip(), 0) for x in text.split(",")]
                except ValueError:
                    raise PathError(f"{path!r}: array index [{text}] must be integers, e.g. [2] or [1, 3]") from None
                dims = list(ty.dims)
                for ix in indices:
                    if not dims:
                        raise PathError(f"{path!r}: too many indices")
                    lo, hi = dims.pop(0)
                    if not lo <= ix <= hi:
                        raise PathError(f"{path!r}: index {ix} outside {lo}..{hi}")
                    if isinstance(key, int):
                        value = container[key]
                    container, key = value, ix - lo
                    value = container[key]
                if dims:
                    ty = t.ArrayType(ty.name, ty.element, tuple(dims))
                else:
                    ty = ty.element
        return container, key, ty


def _through_reference(container: Any, key: Any, path: str) -> tuple[Any, Any]:
    """Follow a VAR_IN_OUT to the variable it refers to (what the FB was last called with)."""
    inner = getattr(container, key)
    if inner is None:
        raise UnboundInOut(f"{path!r}: the in-out is not bound yet (the FB instance has not been called)")
    while isinstance(inner, MapRef):
        inner = inner.ref
    if isinstance(inner, AttrRef):
        return inner.obj, inner.attr
    if isinstance(inner, ItemRef):
        return inner.lst, inner.index
    return container, key   # an aggregate in-out holds the caller's object itself
