"""Stage 3: lower the checked project to one Python module, with a map back to ST lines.

Each FUNCTION_BLOCK/PROGRAM becomes a class (variables are slots `v_<name>`, the body is
`__call__`), each FUNCTION a Python function with a frame object, each STRUCT a class with
`_copy`/`_assign`. One Python statement group per ST statement; `LineMap` maps every generated
line to the ST statement's span, so faults and breakpoints speak ST.

Safety: only names from `lower.names` and `repr()`-ed literals of checked Python types are
written; no ST text is ever copied into the generated source.

Two passes, as CPython's symtable before its compiler: `analysis.plan_project` first decides, per
POU, what the code needs (variables used, assigned, passed by reference, cached in locals;
range-safe FOR loops; inlined and direct FB calls; statements that catch errors), then the
generators write it, reading that plan (`self.plan`). The generators live beside this module, one
per kind of thing they write: `gen_pou` (units and call bodies), `gen_stmt` (statements),
`gen_expr` (expressions); `pycode` holds the line writer and literal helpers, `options` the
switchable optimisations. `Lowerer` joins them and holds the state of one lowering run.
"""

from __future__ import annotations

from stvm.semantics import types as t
from stvm.semantics.checker import Analysis
from stvm.semantics.model import POUInfo, Variable
from stvm.lower.analysis import EMPTY_PLAN, ProjectPlan, plan_project
from stvm.lower.gen_expr import ExpressionGenerator
from stvm.lower.gen_pou import PouGenerator
from stvm.lower.gen_stmt import StatementGenerator
from stvm.lower.layout import build_layout
from stvm.lower.names import unit_name
from stvm.lower.options import DEFAULT_OPTIONS, LowerOptions
from stvm.lower.pycode import CodeWriter
from stvm.syntax import nodes as n
from stvm.lower.product import LineMap, LoweredProject  # noqa: F401 (API)


class Lowerer(PouGenerator, StatementGenerator, ExpressionGenerator):
    """One lowering run: the names of every unit, the module being written, and the state of the
    POU being lowered (its cached locals, loops and range-FOR variables)."""

    def __init__(self, analysis: Analysis, settings, options: LowerOptions = DEFAULT_OPTIONS) -> None:
        self.a = analysis
        self.model = analysis.model
        self.facts = analysis.facts
        self.settings = settings
        self.w = CodeWriter()
        self.classes: dict[str, str] = {}
        self.natives: dict[str, str] = {}
        self.native_fbs: dict[str, str] = {}
        self.types: list[t.Type] = []
        self.sites: list[n.Span] = []
        self.tmp = 0
        # per-POU state
        self.pou: POUInfo | None = None
        self.owner = "self"
        self.loops: list[tuple[str, list[str]]] = []   # (kind, continue-code lines)
        # Variables held in Python locals during a call (the plan's `PouPlan.cached`): key →
        # Variable, and which of them the code written read / assigned (for the prologue and the
        # write-back: exactly the locals the emitted code touches).
        self.cached: dict[str, Variable] = {}
        self.used: set[str] = set()
        self.assigned: set[str] = set()
        self.options = options
        # the analysis pass's decisions (`lower` computes them first; expressions lowered on their
        # own, as the debugger's, need none)
        self.plan: ProjectPlan = EMPTY_PLAN
        # loop variables of range-FORs in scope: key → (step, constant start or None, type)
        self.range_vars: dict[str, tuple[int, int | None, t.IntType]] = {}
        self.unchecked: set[str] = set()   # range-FOR variables whose array accesses were hoisted
        # references whose scalar target a loop keeps in a Python local (hold_derefs_in_loops):
        # the reference variable's key → the local
        self.held: dict[str, str] = {}
        # `share_struct_sources`: the struct source whose leaves the code just written holds in
        # `_h0`, `_h1`, ... (source code, struct type), and the call statement being written
        # when it may share (`GenStmt.hoist_safe_call`); None otherwise
        self.hoisted: tuple[str, t.StructType, tuple] | None = None
        self.sharing: object | None = None

    def assign_names(self) -> None:
        for i, (key, st) in enumerate(sorted(self.model.structs.items())):
            self.classes[key] = unit_name("S", i, st.qualname)  # type: ignore[attr-defined]
        for i, (key, pou) in enumerate(sorted(self.model.pous.items())):
            if pou.kind == "FUNCTION":
                name = unit_name("N" if pou.native else "F", i, pou.qualname)
                if pou.native:
                    self.natives[name] = pou.qualname.split("\\")[-1].upper()
            else:
                name = unit_name("P", i, pou.qualname)
                if pou.native:
                    self.native_fbs[name] = pou.qualname.split("\\")[-1].upper()
            self.classes[key] = name

    def type_const(self, ty: t.Type) -> str:
        for i, existing in enumerate(self.types):
            if existing == ty and type(existing) is type(ty):
                return f"_T[{i}]"
        self.types.append(ty)
        return f"_T[{len(self.types) - 1}]"

    def types_const(self, types_: tuple[t.Type, ...]) -> str:
        """A tuple of types in `_T` (for `typed` natives)."""
        return "(" + "".join(self.type_const(ty) + ", " for ty in types_) + ")"

    def new_tmp(self, stem: str) -> str:
        self.tmp += 1
        return f"_{stem}{self.tmp}"

    def lower(self) -> LoweredProject:
        self.plan = plan_project(self.a, self.settings, self.options)
        self.assign_names()
        w = self.w
        w.line("# generated by stvm from checked ST; do not edit")
        for key, st in sorted(self.model.structs.items()):
            if isinstance(st, t.UnionType):
                self.union_class(key, st)
            else:
                self.struct_class(key, st)  # type: ignore[arg-type]
        self.globals_class()
        for key, pou in self.class_order():
            node = self.a.pou_nodes.get(key)
            if pou.kind == "FUNCTION":
                if not pou.native:
                    self.function(pou, node)
            elif pou.kind != "INTERFACE":
                self.fb_class(pou, node)
        # the layout (lower/layout.py) is computed from the model with the same `names` the
        # generator used, not collected while emitting: readers need neither the generator nor facts
        return LoweredProject("\n".join(w.lines) + "\n", w.line_map, self.classes, self.natives,
                              self.native_fbs, self.types, self.sites, layouts=build_layout(self.model))


def lower_project(analysis: Analysis, settings, options: LowerOptions = DEFAULT_OPTIONS) -> LoweredProject:
    """Generate the Python module for a checked project."""
    return Lowerer(analysis, settings, options).lower()
