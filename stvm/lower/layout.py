"""Where the generated code keeps each ST variable: the one layout every reader goes through.

Lowering publishes, per POU, struct and for the globals, a `PouLayout`: ST variable (by its
lower-case key) → `VarSlot(name, storage, type, section)`. `storage` is the Python attribute on the
instance (FB/PROGRAM), the struct object, the globals object, or the local/frame name inside a
FUNCTION call. The VM's path access (`stvm.runtime.access`), the value formatter, the tracer, the
debugger and the DAP server read variables only through these slots, so the storage names are
built in one place (`stvm.lower.names`) and a change of naming scheme touches nothing else.

Why a plain data structure computed from the checked model, and not facts collected while code is
emitted: the layout is the same for every optimisation of the generator (cached locals, hoisted
checks), it travels in the compile cache with the `LoweredProject` as the model it is a function
of (each `PouLayout` is built when first read), and the readers (which run long after lowering,
often from the cache) need neither the generator nor the checker behind it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import Any, Callable, Iterator

from stvm.lower.names import is_var_attr, var_attr
from stvm.semantics import types as t

FIELD = "FIELD"           # section of a STRUCT member
GLOBALS_KEY = ""          # `ProjectLayout.globals.pou`: the VAR_GLOBALs of the project


def is_storage_name(attr: str) -> bool:
    """Whether `attr` is a storage name of some slot's kind (readers that write storage names into
    generated text, such as the trace sampler, check every name with it)."""
    return is_var_attr(attr)


@dataclass(frozen=True)
class VarSlot:
    """One ST variable (pin, local, struct field or global) and where the generated code keeps it."""

    name: str        # the declared spelling (`Prg_Step`)
    storage: str     # attribute / local name in the generated code (`v_prg_step`)
    type: t.Type
    section: str     # VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR, VAR_TEMP, VAR_EXTERNAL, VAR_GLOBAL, FIELD

    @property
    def is_alias(self) -> bool:
        """The slot refers to storage elsewhere (a VAR_IN_OUT's reference, a VAR_EXTERNAL's global):
        walks over "every variable" skip it, an explicit path follows it."""
        return self.section in ("VAR_IN_OUT", "VAR_EXTERNAL")


@dataclass(frozen=True)
class PouLayout:
    """The slots of one POU, struct type or of the globals, in declaration order."""

    pou: str                                  # qualname as declared ("" for the globals)
    kind: str                                 # PROGRAM, FUNCTION_BLOCK, FUNCTION, STRUCT, GLOBALS
    slots: dict[str, VarSlot]                 # lower-case ST name → slot
    aliases: dict[str, str] = field(default_factory=dict)   # Omron pin alias key → slot key
    type: t.Type | None = None                # a STRUCT's declared type (a placeholder resolves to it)

    def slot(self, name: str) -> VarSlot | None:
        """The slot of ST name `name` (case-insensitive, pin aliases such as Omron's `In` for IN)."""
        key = name.lower()
        return self.slots.get(self.aliases.get(key, key))

    def __iter__(self) -> Iterator[VarSlot]:
        return iter(self.slots.values())

    def owned(self) -> Iterator[VarSlot]:
        """The slots whose storage is on this object itself (not a VAR_IN_OUT / VAR_EXTERNAL alias)."""
        return (s for s in self.slots.values() if not s.is_alias)


class _OnDemand(Mapping[str, PouLayout]):
    """key → layout, each built from its source (a POU, a struct type) the first time it is read."""

    __slots__ = ("_sources", "_build", "_built")

    def __init__(self, sources: dict[str, Any], build: Callable[[Any], PouLayout]) -> None:
        self._sources = sources
        self._build = build
        self._built: dict[str, PouLayout] = {}

    def __getitem__(self, key: str) -> PouLayout:
        # readers on other threads (HMI, OPC UA) may build one twice: both builds are equal
        layout = self._built.get(key)
        if layout is None:
            layout = self._built[key] = self._build(self._sources[key])
        return layout

    def get(self, key: str, default: Any = None) -> Any:   # (Mapping's goes through a KeyError)
        layout = self._built.get(key)
        if layout is not None:
            return layout
        return self[key] if key in self._sources else default

    def __contains__(self, key: object) -> bool:
        return key in self._sources

    def __iter__(self) -> Iterator[str]:
        return iter(self._sources)

    def __len__(self) -> int:
        return len(self._sources)


class ProjectLayout:
    """Every layout of a lowered project (published as `LoweredProject.layouts`).

    Each layout is a pure function of the checked model and `stvm.lower.names`, built the first
    time it is read and kept: a program reads the layouts of the few POUs it instantiates, while
    the stdlib brings hundreds. The pickle (the compile cache) holds only the model, which the cache
    entry holds anyway: pickling every layout made a cached load ~15 ms slower for the thesis."""

    def __init__(self, model) -> None:
        self.model = model      # stvm.semantics.model.ProjectModel

    def __getstate__(self) -> dict:
        return {"model": self.model}

    @cached_property
    def pous(self) -> Mapping[str, PouLayout]:
        """POU/METHOD key (lower-case qualname) → layout."""
        return _OnDemand(_pou_sources(self.model), pou_layout)

    @cached_property
    def structs(self) -> Mapping[str, PouLayout]:
        """Struct key → layout."""
        return _OnDemand({key: st for key, st in self.model.structs.items() if isinstance(st, t.StructType)},
                         struct_layout)

    @cached_property
    def globals(self) -> PouLayout:
        """The VAR_GLOBALs (on the generated globals object)."""
        return PouLayout(GLOBALS_KEY, "GLOBALS",
                         {key: VarSlot(var.name, var_attr(var.name), var.type, var.section)
                          for key, var in self.model.globals.items()})

    def of(self, ty: t.Type | None) -> PouLayout | None:
        """The layout of values of type `ty`: an FB/PROGRAM instance or a STRUCT; None otherwise."""
        if isinstance(ty, t.FBType):
            return self.pous.get(ty.qualname.lower())
        if isinstance(ty, t.StructType):
            known = self.structs.get(ty.qualname.lower()) if ty.qualname else None
            if known is not None and known.type is ty:
                return known   # the declared type itself (the usual case: no comparison)
            # a struct placeholder (self-reference) has no fields of its own: the declared one has
            if known is not None and (not ty.fields or _field_names(ty) == tuple(known.slots)):
                return known
            return struct_layout(ty)
        return None


def _field_names(ty: t.StructType) -> tuple[str, ...]:
    return tuple(name.lower() for name, _ in ty.fields)


def struct_layout(ty: t.StructType) -> PouLayout:
    """The layout of a struct type on its own (a value formatted without a project at hand)."""
    return PouLayout(ty.qualname or ty.name, "STRUCT",
                     {name.lower(): VarSlot(name, storage, fty, FIELD)
                      for (name, fty), storage in zip(ty.fields, _storage_of(tuple(n for n, _ in ty.fields)))},
                     type=ty)


@lru_cache(maxsize=4096)
def _storage_of(names: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(var_attr(name) for name in names)


def pou_layout(pou) -> PouLayout:
    """The layout of a checked POU (`stvm.semantics.model.POUInfo`): its variables, inherited ones
    first; a VAR_EXTERNAL's storage is the global's (on the globals object, not the instance)."""
    return PouLayout(pou.qualname, pou.kind,
                     {key: VarSlot(var.name, var_attr(var.name), var.type, var.section)
                      for key, var in pou.variables.items()},
                     dict(pou.aliases))


def _pou_sources(model) -> dict[str, Any]:
    """Every POU with storage by key; a METHOD's (and a property accessor's) own variables live on
    its call's frame, under its own key (`fb.method`, `fb.__get_prop`): the debugger shows them."""
    sources: dict[str, Any] = {}
    for key, pou in model.pous.items():
        if pou.kind == "INTERFACE":
            continue    # no storage: an interface variable holds an FB instance
        sources[key] = pou
        for method in pou.methods.values():
            sources[method.key] = method
        for prop in pou.properties.values():
            for accessor in (prop.getter, prop.setter):
                if accessor is not None:
                    sources[accessor.key] = accessor
    return sources


def build_layout(model) -> ProjectLayout:
    """The layout of every POU, struct and global of a checked `ProjectModel`."""
    return ProjectLayout(model)
