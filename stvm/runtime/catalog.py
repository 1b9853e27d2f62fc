"""The one catalog of a running project's variables: what the trace, the debugger, DAP, the HMI
and OPC UA list, in one order, with one set of skip rules and one path syntax.

Before this module each front end walked the variable tree itself, and the walks had drifted
apart (the HMI/OPC UA listed programs first and a program's VAR_IN_OUT, the trace listed globals
first, DAP showed an FB's VAR_TEMP and VAR_IN_OUT members, the trace and OPC UA wrote `a[1, 2]`
and `a[1,2]` for the same element). Now they all read this tree.

Order: the globals (declaration order), then the program instances (task order), each followed,
depth first, by what is below it: struct fields and FB members in declaration order (inherited
members first), array elements in row-major order (last index fastest).

Skip rules (one set, `LISTED` / `listed_slots`):

* VAR_TEMP: lives only during a call; between two calls it holds nothing the program can see.
* VAR_IN_OUT and VAR_EXTERNAL: aliases of a variable that is listed where it is declared. A path
  through one still resolves (`stvm.runtime.access`), it is only not listed twice.
* References, pointers and interface variables are leaves: what they point to is listed where it
  is declared, and `r^` resolves by path.
* An array of more than `MAX_ARRAY_ELEMENTS` elements is listed without its elements (a front end
  would publish 10,000 nodes); its elements still resolve by path.

Path syntax (`element_path`): `Global.field`, `Instance.var.member`, `arr[3]`, `grid[1,2]` --
names as declared, indices without spaces, the form the strict path reader
(`stvm.runtime.paths`) reads, one shell word and a valid VCD identifier. Each node knows how to
reach its value from a root object (`root`, `steps`: the layout's storage names and list
offsets), which the trace's compiled sampler and the debugger's instance map use; reading by path
goes through `stvm.runtime.access` (`vm.resolve`), which resolves every path listed here.

A running call's own variables (the debugger's and DAP's frame scopes) are not this tree: they are
listed by `call_slots`, beside the catalog's rules so the two are read in one place.
"""

from __future__ import annotations

from functools import cached_property
from itertools import product
from typing import Any, Iterator

from stvm.lower.layout import PouLayout, VarSlot
from stvm.runtime import paths
from stvm.semantics import types as t

MAX_ARRAY_ELEMENTS = 10_000
"""Arrays with more elements than this are listed without their elements."""

ELEMENTARY_KINDS = frozenset({"bool", "int", "real", "time", "string", "enum"})
"""Type kinds a front end shows as one value (a trace records them); the other leaves are
references, pointers and interfaces."""

SKIPPED_SECTIONS = frozenset({"VAR_TEMP", "VAR_IN_OUT", "VAR_EXTERNAL"})
"""Sections the catalog does not list (module docstring: why)."""


def listed_slots(layout: PouLayout | None) -> Iterator[VarSlot]:
    """The members of a struct, FB or program layout the catalog lists, in declaration order."""
    return (slot for slot in (layout if layout is not None else ()) if slot.section not in SKIPPED_SECTIONS)


def call_slots(layout: PouLayout) -> Iterator[VarSlot]:
    """The variables of a running call of a POU (a stack frame's scope): every slot but a
    VAR_EXTERNAL (the global, listed with the globals) and a METHOD's VAR_INST (stored on the
    instance, shown under THIS)."""
    return (slot for slot in layout if slot.section not in ("VAR_EXTERNAL", "VAR_INST"))


def index_text(indices: tuple[int, ...] | list[int]) -> str:
    """`1,2`: the indices of one element as every path of the catalog writes them."""
    return ",".join(str(i) for i in indices)


def element_path(path: str, indices: tuple[int, ...] | list[int]) -> str:
    """The path of one array element: `Main.grid[1,2]`."""
    return f"{path}[{index_text(indices)}]"


def lists_elements(ty: t.Type) -> bool:
    """Whether the catalog lists the elements of an array of type `ty`."""
    return isinstance(ty, t.ArrayType) and bool(ty.dims) and ty.length <= MAX_ARRAY_ELEMENTS


_AGGREGATES = (t.StructType, t.FBType, t.ArrayType)


class VariableInfo:
    """One node of the catalog: a program instance, a global, or a variable below one."""

    __slots__ = ("name", "path", "type", "section", "kind", "in_fb", "constant", "root", "steps",
                 "_catalog", "_children")

    def __init__(self, catalog: "Catalog", name: str, path: str, ty: t.Type, section: str, kind: str,
                 in_fb: bool, constant: bool, root: Any, steps: tuple) -> None:
        self.name = name            # the user's spelling of the last part (`X`, `[2]`, `[1,2]`)
        self.path = path            # stvm path: `PnP_Example_Instance.Prg_Step`, `Arr[2].X`
        self.type = ty
        self.section = section      # declaring section (VAR_INPUT, VAR_GLOBAL, …; PROGRAM for a program)
        self.kind = kind            # program | global | variable | member | element
        self.in_fb = in_fb          # lies inside an FB instance (an "FB internal")
        self.constant = constant    # declared CONSTANT (the root variable or the FB member)
        self.root = root            # the program instance or the globals object the steps start from
        self.steps = steps          # storage names and list offsets from `root` to the value
        self._catalog = catalog
        self._children: list[VariableInfo] | None = None

    def __repr__(self) -> str:
        return f"VariableInfo({self.path!r}, {self.type.name}, {self.kind})"

    @property
    def leaf(self) -> bool:
        """An elementary value (a front end shows or writes it), not a struct, array or FB."""
        return not isinstance(self.type, _AGGREGATES)

    @property
    def children(self) -> list["VariableInfo"]:
        """The nodes right below this one, built the first time they are read (readers on two
        threads may both build them: the lists are equal)."""
        children = self._children
        if children is None:
            children = self._children = self._catalog.children_of(self)
        return children

    def walk(self) -> Iterator["VariableInfo"]:
        """This node and every node below it, depth first."""
        stack = [self]
        while stack:
            node = stack.pop()
            yield node
            stack.extend(reversed(node.children))

    def read(self) -> Any:
        """The current value (the object itself for a struct, FB instance or array)."""
        value = self.root
        for step in self.steps:
            value = value[step] if isinstance(step, int) else getattr(value, step)
        return value


class Catalog:
    """The variables of one running VM (its globals and program instances never change)."""

    def __init__(self, vm: Any) -> None:
        self.vm = vm
        self.layouts = vm.layouts
        self.model = vm.model

    @cached_property
    def roots(self) -> list[VariableInfo]:
        """The globals (declaration order), then the program instances (task order)."""
        vm = self.vm
        roots: list[VariableInfo] = []
        for key, slot in self.layouts.globals.slots.items():
            var = self.model.globals.get(key)
            roots.append(VariableInfo(self, slot.name, slot.name, slot.type, slot.section, "global", False,
                                      bool(var is not None and var.constant), vm.globals, (slot.storage,)))
        for name, inst, qualname in vm.instances.values():
            pou = self.model.pous[qualname.lower()]
            roots.append(VariableInfo(self, name, name, t.FBType(pou.name, qualname, True), "PROGRAM", "program",
                                      False, False, inst, ()))
        return roots

    def walk(self) -> Iterator[VariableInfo]:
        """Every node, in catalog order."""
        for root in self.roots:
            yield from root.walk()

    def node(self, path: str) -> VariableInfo | None:
        """The node a path names (read by the strict path reader, case-insensitive), or None when
        the path is not in the catalog (a VAR_IN_OUT member, `r^`, an element of a huge array)."""
        try:
            tokens = paths.parse_path(path)
        except paths.PathSyntaxError:
            return None
        nodes = self.roots
        found: VariableInfo | None = None
        for kind, text in tokens:
            if kind == "deref":
                return None
            if kind == "name":
                key = text.lower()
                found = next((c for c in nodes if c.kind != "element" and c.name.lower() == key), None)
            else:
                key = f"[{text}]"
                found = next((c for c in nodes if c.kind == "element" and c.name == key), None)
            if found is None:
                return None
            nodes = found.children
        return found

    def detached(self, path: str, ty: t.Type, root: Any, steps: tuple = (), section: str = "VAR") -> VariableInfo:
        """A node for a value the tree does not list (reached through a VAR_IN_OUT or a reference,
        or a debugger frame's variable), whose children follow the catalog's rules."""
        return VariableInfo(self, path.rpartition(".")[2], path, ty, section, "variable", False, False, root, steps)

    def members(self, ty: t.Type) -> list[VarSlot]:
        """The listed members of a struct or FB type (none for anything else)."""
        if not isinstance(ty, (t.StructType, t.FBType)):
            return []
        return list(listed_slots(self.layouts.of(ty)))

    # ---- building
    def children_of(self, node: VariableInfo) -> list[VariableInfo]:
        ty = node.type
        out: list[VariableInfo] = []
        if not isinstance(ty, _AGGREGATES):
            return out
        if isinstance(ty, (t.StructType, t.FBType)):
            layout = self.layouts.of(ty)
            is_fb = isinstance(ty, t.FBType)
            pou = self.model.pous.get(ty.qualname.lower()) if is_fb else None
            kind = "variable" if node.kind == "program" else "member"
            in_fb = node.in_fb or (is_fb and not ty.is_program)
            for key, slot in (layout.slots.items() if layout is not None else ()):
                if slot.section in SKIPPED_SECTIONS:
                    continue
                if is_fb:
                    var = pou.variables.get(key) if pou is not None else None
                    section = slot.section
                    constant = node.constant or bool(var is not None and var.constant)
                else:      # a struct field belongs to the variable that holds the struct
                    section, constant = node.section, node.constant
                out.append(VariableInfo(self, slot.name, f"{node.path}.{slot.name}", slot.type, section, kind,
                                        in_fb, constant, node.root, node.steps + (slot.storage,)))
        elif lists_elements(ty):
            assert isinstance(ty, t.ArrayType) and ty.dims
            element, path, steps = ty.element, node.path, node.steps
            if len(ty.dims) == 1:   # (most arrays: no index tuples to build)
                lo, hi = ty.dims[0]
                for i in range(lo, hi + 1):
                    out.append(VariableInfo(self, f"[{i}]", f"{path}[{i}]", element, node.section, "element",
                                            node.in_fb, node.constant, node.root, steps + (i - lo,)))
                return out
            lows = [lo for lo, _ in ty.dims]
            for index in product(*(range(lo, hi + 1) for lo, hi in ty.dims)):
                offsets = tuple(i - lo for i, lo in zip(index, lows))
                text = index_text(index)
                out.append(VariableInfo(self, f"[{text}]", f"{path}[{text}]", element, node.section,
                                        "element", node.in_fb, node.constant, node.root, steps + offsets))
        return out


def catalog(vm: Any) -> list[VariableInfo]:
    """The roots of `vm`'s catalog: the globals, then the program instances (module docstring)."""
    return Catalog(vm).roots
