"""Stage 2: index every declaration, resolve names and types, collect every error in one pass.

`analyze(units)` first indexes every type, POU and global of all units (so file order and
declaration order never matter), then checks each POU body. It never raises for bad ST: each
problem is a `Diagnostic`. For the code generator it records, per expression node, its type and
what a name refers to (`Facts`).

`Checker` runs the passes in order (docs/architecture.md, "Checker passes"): the index
(index.py), type resolution and constants (resolve.py, constants.py), declarations, instance
initialisers and object orientation (declarations.py, instance_inits.py, oo.py), the body checks
(body.py) and the whole-program rules (program.py). They share one `CheckContext` (context.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from stvm.diagnostics import Diagnostic
from stvm.semantics import types as t
from stvm.semantics.body import BodyChecker
from stvm.semantics.context import CheckContext
from stvm.semantics.facts import NOT_CONST, CallInfo, Facts, NameRef  # noqa: F401 (API: checker.Facts)
from stvm.semantics.index import DeclarationIndex, Indexer
from stvm.semantics.qualified import resolve as resolve_qualified
from stvm.semantics.model import ProjectModel
from stvm.settings import DEFAULT_SETTINGS, SysmacSettings
from stvm.syntax import nodes as n
from stvm.semantics.resolve import TypeResolver
from stvm.semantics.constants import ConstantEvaluator
from stvm.semantics.oo import ClassHierarchy
from stvm.semantics.declarations import DeclarationPass
from stvm.semantics.instance_inits import InstanceInits
from stvm.semantics.program import NESTING_LIMIT  # noqa: F401 (API: checker.NESTING_LIMIT)
from stvm.semantics.program import ProgramChecks


@dataclass
class Analysis:
    model: ProjectModel
    facts: Facts
    units: list[n.CompilationUnit]
    pou_nodes: dict[str, n.POU]
    diagnostics: list[Diagnostic]
    type_inits: dict[str, dict[str, object]]   # struct qualname key → field key → initial value
    method_nodes: dict[str, n.Method] = field(default_factory=dict)   # METHOD/GET/SET key → node



def _shared(name: str) -> property:
    """A table of the check's context, read (and, for the debugger's swap of `facts`, replaced)
    through the Checker: the body checker and stvm/debug/scope.py use these names."""
    return property(lambda self: getattr(self.ctx, name), lambda self, value: setattr(self.ctx, name, value))


class Checker:
    """The one entry point of the semantic check: makes the passes over one shared context and
    runs them in order (`run`)."""

    def __init__(self, units: list[n.CompilationUnit], settings: SysmacSettings,
                 natives: Mapping[str, Any] | None = None) -> None:
        # `GVL.x`, `Enum.member`, qualified_only: resolved before anything else (the debug build
        # constructs a Checker too)
        units, qualified = resolve_qualified(list(units))
        self.ctx = CheckContext(units, settings, natives, qualified, DeclarationIndex(settings.dialect))
        self.indexer = Indexer(self.ctx)
        self.types = TypeResolver(self.ctx, self.indexer)
        self.constants = ConstantEvaluator(self.ctx, self.types)
        self.oo = ClassHierarchy(self.ctx)
        self.declarations = DeclarationPass(self.ctx, self.indexer, self.types, self.constants)
        self.instance_inits = InstanceInits(self.ctx, self.constants)
        self.program = ProgramChecks(self.ctx, self.indexer, self.constants, self.oo)

    units = _shared("units")
    settings = _shared("settings")
    natives = _shared("natives")
    diags = _shared("diags")
    facts = _shared("facts")
    index = _shared("index")
    pous = _shared("pous")
    globals = _shared("globals")
    structs = _shared("structs")
    enums = _shared("enums")
    any_static = _shared("any_static")
    type_inits = _shared("type_inits")
    method_nodes = _shared("method_nodes")

    # ---- diagnostics
    def error(self, message: str, span: n.Span, code: str = "") -> None:
        self.ctx.error(message, span, code)

    def warning(self, message: str, span: n.Span, code: str = "") -> None:
        self.ctx.warning(message, span, code)

    def string_overflow(self, length: int, dst: t.StringType, span: n.Span, initial: bool = False) -> None:
        self.ctx.string_overflow(length, dst, span, initial)

    # ---- entry
    def build_index(self) -> None:
        """Passes 1 to 3: index, declare (resolving types and constants as declarations need
        them), link the classes, resolve instance initialisers."""
        self.indexer.build_index()
        self.declarations.declare_all()
        self.oo.link_oo()
        self.instance_inits.resolve_fb_instance_inits()
        self.instance_inits.resolve_fb_init_args()

    def run(self) -> Analysis:
        self.build_index()
        for key, pou in self.ctx.index.pou_nodes.items():
            info = self.ctx.pous[key]
            if info.native:
                if pou.body:
                    self.error(f"native POU '{pou.name}' must not have a body", pou.span, "E025")
                continue
            BodyChecker(self, info, pou).check()
            for method in self.oo.members_of(info):
                BodyChecker(self, method, self.ctx.method_nodes[method.key], fb=info, fb_node=pou).check()
        # the depth check walks iteratively and runs first: the two checks after it recurse,
        # and a chain thousands deep must be a diagnostic naming it, not a RecursionError
        if self.program.check_nesting_depth():
            self.program.check_containment()
            self.program.check_recursion()
            self.program.check_method_recursion()
        tasks, defaults = self.program.check_configuration()
        model = ProjectModel(self.ctx.pous, self.ctx.globals, tasks, defaults, self.ctx.structs, self.ctx.enums)
        return Analysis(model, self.ctx.facts, self.ctx.units, dict(self.ctx.index.pou_nodes), self.ctx.diags,
                        self.ctx.type_inits, self.ctx.method_nodes)


def analyze(units: list[n.CompilationUnit], settings: SysmacSettings = DEFAULT_SETTINGS,
            natives: Mapping[str, Any] | None = None) -> Analysis:
    """Check all units together; returns the model, per-node facts and every diagnostic.

    `natives`: the stdlib's native functions (stvm.stdlib.NATIVE_FUNCTIONS), for the result types
    of generic ones (SHL, MUX, TRUNC, …); without it their result is the common input type."""
    return Checker(units, settings, natives).run()
