"""What the checker's passes share (docs/architecture.md, "Checker passes").

`CheckContext` holds the tables the passes fill and read: the declaration index, the resolved
POUs, globals and types, the per-node facts and the diagnostics. Every pass (`Pass`) gets the one
context of its check, and the other passes it calls, when it is made: no pass reaches another
through the context, so what each pass reads is visible in its constructor.
"""

from __future__ import annotations

from typing import Any, Mapping

from stvm.diagnostics import Diagnostic
from stvm.semantics import types as t
from stvm.semantics.facts import Facts
from stvm.semantics.model import POUInfo, Variable
from stvm.settings import StringOverflow, SysmacSettings
from stvm.syntax import nodes as n


class CheckContext:
    """The state of one check: made by `Checker`, filled pass by pass."""

    def __init__(self, units: list[n.CompilationUnit], settings: SysmacSettings,
                 natives: Mapping[str, Any] | None, diags: list[Diagnostic],
                 index: Any) -> None:
        self.units = units
        self.settings = settings
        # the stdlib's native functions by upper-case name (stvm.stdlib.NATIVE_FUNCTIONS): their
        # result-type rules. Given by the caller, which knows the stdlib; the checker sits below it.
        self.natives = natives if natives is not None else {}
        self.diags = diags
        self.facts = Facts()
        self.index = index   # index.DeclarationIndex (index.py imports this module), filled first
        self.resolved_types: dict[str, t.Type | None] = {}
        self.resolving: set[str] = set()
        self.type_inits: dict[str, dict[str, object]] = {}
        self.pous: dict[str, POUInfo] = {}
        self.globals: dict[str, Variable] = {}
        self.any_static = False    # a VAR_STAT was hoisted to a global (hoist_static_variables)
        self.fb_instance_inits: list = []   # `fb : F := (x := 1)` waiting for F's variables (fb_instance_init)
        self.fb_init_arg_decls: list = []   # `fb : F(1, 2)` waiting for F's FB_init (resolve_fb_init_args)
        self.global_nodes: dict[str, n.VarDecl] = {}
        self.enumerators: dict[str, list[tuple[t.EnumType, int]]] = {}
        self.structs: dict[str, t.Type] = {}
        self.enums: dict[str, t.Type] = {}
        self.declaring: POUInfo | None = None   # the POU whose declarations are being resolved
        self.method_nodes: dict[str, n.Method] = {}     # METHOD / GET / SET key → its node

    # ---- diagnostics
    def error(self, message: str, span: n.Span, code: str = "") -> None:
        self.diags.append(Diagnostic.error(message, span, code))

    def warning(self, message: str, span: n.Span, code: str = "") -> None:
        self.diags.append(Diagnostic.warning(message, span, code))

    def string_overflow(self, length: int, dst: t.StringType, span: n.Span, initial: bool = False) -> None:
        """A constant of `length` bytes stored into `dst` (sysmac.md 2, `string_overflow`): a
        warning (the value is cut at build time), or an error under `string_overflow=error`."""
        unit = "code units" if t.is_wide(dst) else "bytes"
        if self.settings.string_overflow is StringOverflow.ERROR:
            self.error(f"a string of {length} {unit} does not fit {dst.name} ({dst.max_bytes} {unit}; "
                       "string_overflow=error)", span, "E054")
        elif initial:
            self.warning(f"initial value truncated to {dst.max_bytes} {unit} of {dst.name}", span, "W001")
        else:
            self.warning(f"a string of {length} {unit} is truncated to the {dst.max_bytes} {unit} of {dst.name}",
                         span, "W001")


class Pass:
    """A pass of the checker: reads and fills `ctx`; reports through it."""

    def __init__(self, ctx: CheckContext) -> None:
        self.ctx = ctx

    def error(self, message: str, span: n.Span, code: str = "") -> None:
        self.ctx.error(message, span, code)

    def warning(self, message: str, span: n.Span, code: str = "") -> None:
        self.ctx.warning(message, span, code)

    def string_overflow(self, length: int, dst: t.StringType, span: n.Span, initial: bool = False) -> None:
        self.ctx.string_overflow(length, dst, span, initial)
