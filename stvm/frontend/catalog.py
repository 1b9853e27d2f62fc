"""Every variable of a running project that a front end can publish, as a tree.

Roots are one node per program instance and one per global variable; below them struct fields,
array elements and FB instance members. Each node knows its stvm path (the one `--print`
accepts), its ST type, the section it was declared in and whether it is a leaf (an elementary
value a front end shows or writes).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product

from stvm.runtime.vm import VM
from stvm.semantics import types as t
from stvm.semantics.model import EXTERNAL, GLOBAL, IN_OUT, TEMP

MAX_ARRAY_ELEMENTS = 10_000
"""Arrays with more elements than this are listed without their elements."""


@dataclass
class VariableInfo:
    name: str                     # the user's spelling of the last part (`X`, `[2]`)
    path: str                     # stvm path: `PnP_Example_Instance.Prg_Step`, `Arr[2].X`
    type: t.Type
    section: str                  # the declaring section of the root variable (VAR_INPUT, VAR_GLOBAL, …)
    kind: str                     # program | global | variable | member | element
    in_fb: bool = False           # lies inside an FB instance (an "FB internal")
    constant: bool = False        # declared CONSTANT (the root variable or the FB member)
    children: list["VariableInfo"] = field(default_factory=list)

    @property
    def leaf(self) -> bool:
        return not isinstance(self.type, (t.StructType, t.ArrayType, t.FBType))

    def walk(self):
        """This node and every node below it, depth first."""
        yield self
        for child in self.children:
            yield from child.walk()


def catalog(vm: VM) -> list[VariableInfo]:
    """Program instances (in task order), then globals (in declaration order)."""
    roots: list[VariableInfo] = []
    pous = vm.model.pous
    for name, _inst, qualname in vm.instances.values():
        pou = pous[qualname.lower()]
        node = VariableInfo(name, name, t.FBType(pou.name, qualname, True), "PROGRAM", "program")
        for var in pou.variables.values():
            if var.section in (TEMP, EXTERNAL):
                continue   # TEMP lives only during a call; EXTERNAL is listed under the globals
            node.children.append(_node(vm, var.name, f"{name}.{var.name}", var.type, var.section,
                                       "variable", False, var.constant))
        roots.append(node)
    for var in vm.model.globals.values():
        roots.append(_node(vm, var.name, var.name, var.type, GLOBAL, "global", False, var.constant))
    return roots


def _node(vm: VM, name: str, path: str, ty: t.Type, section: str, kind: str, in_fb: bool,
          constant: bool = False) -> VariableInfo:
    node = VariableInfo(name, path, ty, section, kind, in_fb, constant)
    if isinstance(ty, t.StructType):
        for field_name, field_type in ty.fields:
            node.children.append(_node(vm, field_name, f"{path}.{field_name}", field_type, section,
                                       "member", in_fb, constant))
    elif isinstance(ty, t.ArrayType) and ty.dims and ty.length <= MAX_ARRAY_ELEMENTS:
        for index in product(*(range(lo, hi + 1) for lo, hi in ty.dims)):
            text = ", ".join(str(i) for i in index)
            node.children.append(_node(vm, f"[{text}]", f"{path}[{text}]", ty.element, section,
                                       "element", in_fb, constant))
    elif isinstance(ty, t.FBType) and not ty.is_program:
        pou = vm.model.pous.get(ty.qualname.lower())
        for var in (pou.variables.values() if pou else ()):
            if var.section in (TEMP, EXTERNAL, IN_OUT):
                continue   # an in-out is a reference to a variable listed elsewhere
            node.children.append(_node(vm, var.name, f"{path}.{var.name}", var.type, var.section,
                                       "member", True, constant or var.constant))
    return node
