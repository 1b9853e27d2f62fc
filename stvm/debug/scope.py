"""ST expressions and assignments for the debugger, in the scope of one POU instance.

`print`, `watch`, `set`, `force` and breakpoint conditions are ST text. Each is parsed with
`parse_expression`, typed by the project's own body checker in the scope of the POU the debugger
stands in, and lowered by the project's own code generator, so it means exactly what the same text
would mean in that POU's body (integer wrap, REAL rounding, enum literals, function calls).

Debugger scope rules, wider than a POU body's on purpose:

* every variable of an FB instance is readable and assignable from outside (`fb.Step`, not only
  its inputs and outputs), since inspecting internals is what a debugger is for;
* program instances are names everywhere (`Program_Example_Instance.Connect_Done`), after the
  POU's own variables and the globals;
* outside any POU (stopped between scans) only globals, program instances and enumerators are
  in scope.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from types import CodeType, SimpleNamespace
from typing import Any

from stvm.lower.codegen import Lowerer
from stvm.lower.layout import VarSlot
from stvm.lower.names import var_attr
from stvm.semantics import types as t
from stvm.semantics.body import BodyChecker
from stvm.semantics.facts import Facts, NameRef
from stvm.semantics.model import EXTERNAL, GLOBAL, IN_OUT, POUInfo, Variable
from stvm.syntax import nodes as n
from stvm.syntax import parse_expression
from stvm.runtime.values import FunctionError, STFault
from stvm.debug.build import DEBUG_OPTIONS

EXPR_FILENAME = "<stvm-debug>"   # never GENERATED_FILENAME: the tracer must not step into these


class DebugError(Exception):
    """A debugger command that cannot be done; the message is for the user."""


def is_scalar_ref(var: Variable | VarSlot) -> bool:
    """A scalar VAR_IN_OUT: the instance holds a reference object (`get()`/`set()`)."""
    return var.section == IN_OUT and not isinstance(var.type, (t.StructType, t.ArrayType, t.FBType))


class GlobalsView:
    """What `_G` is for debugger code: the globals, plus the program instances by name."""

    __slots__ = ("_globals", "_programs")

    def __init__(self, globals_obj: Any, programs: dict[str, Any]) -> None:
        object.__setattr__(self, "_globals", globals_obj)
        object.__setattr__(self, "_programs", programs)

    def __getattr__(self, attr: str) -> Any:
        programs = object.__getattribute__(self, "_programs")
        if attr in programs:
            return programs[attr]
        return getattr(object.__getattribute__(self, "_globals"), attr)

    def __setattr__(self, attr: str, value: Any) -> None:
        setattr(object.__getattribute__(self, "_globals"), attr, value)


@dataclass
class Scope:
    """Where an expression is evaluated: a POU instance (FB/PROGRAM: `instance`), a FUNCTION call
    (`frame` holds its variables, `result` its return value so far), or nowhere (pou None)."""

    pou: POUInfo | None = None
    node: n.POU | None = None
    instance: Any = None
    frame: Any = None
    result: Any = None
    path: str = ""                 # instance path (`Program_Example_Instance.CBT_MoveAbsolute_Instance`)

    @property
    def owner(self) -> str:
        return "_f" if self.pou is not None and self.pou.kind in ("FUNCTION", "METHOD") else "self"

    def key(self) -> str:
        return self.pou.key if self.pou is not None else ""


@dataclass
class Compiled:
    """An expression lowered for one POU (reusable for every instance of it)."""

    text: str
    code: CodeType
    type: t.Type
    pou_key: str


@dataclass
class CompiledStore:
    """`target := value` lowered for one POU: `value_code` computes the value (converted to the
    target's type), `store_code` stores the local `_value` into the target."""

    target_text: str
    value_code: CodeType
    store_code: CodeType
    type: t.Type
    root_is_local: bool            # the target is a variable of the POU (not a global/program)
    canonical: str                 # normalised target text, for matching `unforce`


_GLOBAL_POU = POUInfo("<debugger>", "<debugger>", "PROGRAM", None)
_GLOBAL_NODE = n.POU("PROGRAM", "<debugger>", (), None, (), (), ())


class _ScopeChecker(BodyChecker):
    """The body checker with the debugger's wider scope rules (module docstring)."""

    def __init__(self, checker, pou: POUInfo, node: n.POU, programs: dict[str, tuple[str, str]]) -> None:
        owner = checker.pous.get(pou.owner) if pou.kind == "METHOD" else None
        super().__init__(checker, pou, node, fb=owner,
                         fb_node=checker.index.pou_nodes.get(pou.owner) if owner is not None else None)
        self.programs = programs            # lower-case instance name → (name, program qualname)

    def resolve_name(self, name: n.Name) -> object:
        ref = super().resolve_name(name)
        if ref is None and len(name.parts) == 1 and not name.rooted:
            found = self.programs.get(name.parts[0].lower())
            if found is not None:
                inst_name, qual = found
                fbt = t.FBType(qual.split("\\")[-1], qual, True)
                return NameRef("global", Variable(inst_name, GLOBAL, fbt))
        return ref

    def member_visible(self, base: t.FBType, var: Variable, e: n.Member) -> bool:
        # the debugger sees every variable of an instance; a VAR_EXTERNAL is the global itself
        if var.section == EXTERNAL:
            self.error(f"'{e.name}' is the global {var.name}; write it without the instance", e.span, "E034")
            return False
        return True

    def lvalue(self, target: n.Expr) -> t.Type | None:
        if isinstance(target, n.Member):
            ty = self.expr(target)
            if ty is not None and self.is_constant_path(target.base):
                self.error("cannot assign to a member of a constant", target.span, "E050")
            if isinstance(ty, t.FBType):
                self.error("function block instances cannot be assigned", target.span, "E052")
                return None
            return ty
        if isinstance(target, n.Name):
            ref = self.resolve_name(target)
            if ref is not None and getattr(ref, "kind", "") == "result":
                self.error("a FUNCTION's result cannot be changed from the debugger", target.span, "E050")
                return None
        return super().lvalue(target)


class _ScopeLowerer(Lowerer):
    """The code generator for debugger text: FB members of every section, scalar in-outs read and
    written through their reference objects."""

    def fb_member(self, e: n.Member) -> Variable | None:
        base_type = self.facts.types.get(e.base.nid)
        if isinstance(base_type, t.FBType):
            pou = self.model.pous.get(base_type.qualname.lower())
            return pou.pin(e.name) if pou is not None else None
        return None

    def ex_Member(self, e: n.Member) -> str:
        var = self.fb_member(e)
        if var is not None and is_scalar_ref(var):
            return f"{self.expr(e.base)}.{var_attr(var.name)}.get()"
        return super().ex_Member(e)

    def store_code(self, target: n.Expr, value: str, ty: t.Type | None) -> list[str]:
        if isinstance(target, n.Member):
            var = self.fb_member(target)
            if var is not None and is_scalar_ref(var):
                return [f"{self.expr(target.base)}.{var_attr(var.name)}.set({value})"]
        return super().store_code(target, value, ty)


class ScopeCompiler:
    """Types and lowers debugger text with the project's checker and code generator.

    One instance per debug session; `compile_*` may be called from any thread (one at a time: the
    checker's fact tables are swapped for each call)."""

    def __init__(self, build) -> None:
        self.build = build
        self.checker = build.checker
        self.model = build.analysis.model
        self.settings = build.project.settings
        self.types: list[t.Type] = list(build.project.lowered.types)   # `_T`, extended by expressions
        self.programs: dict[str, tuple[str, str]] = {}
        self._views: dict[int, tuple[Any, GlobalsView]] = {}
        self._lock = threading.Lock()

    def set_programs(self, instances: dict[str, tuple[str, Any, str]]) -> None:
        self.programs = {key: (name, qual) for key, (name, _, qual) in instances.items()}

    # ---- parsing
    def parse(self, text: str) -> n.Expr:
        if len(text) > MAX_EXPRESSION_CHARS:
            raise DebugError(f"the expression is {len(text)} characters long, more than the debugger takes "
                             f"({MAX_EXPRESSION_CHARS})")
        expr, diags = parse_expression(text.strip(), EXPR_FILENAME, self.settings)
        errors = [d for d in diags if d.is_error]
        if expr is None or errors:
            raise DebugError(_messages(errors or diags, text) or f"cannot parse {_shown(text)}")
        if _tree_depth(expr) > MAX_EXPRESSION_DEPTH:
            raise DebugError(f"the expression is nested more than {MAX_EXPRESSION_DEPTH} levels deep "
                             f"(operators, brackets, calls), more than the debugger takes")
        return expr

    # ---- checking and lowering
    def _session(self, scope: Scope):
        pou = scope.pou or _GLOBAL_POU
        node = scope.node or _GLOBAL_NODE
        facts = Facts()
        saved_facts, saved_diags = self.checker.facts, len(self.checker.diags)
        self.checker.facts = facts
        checker = _ScopeChecker(self.checker, pou, node, self.programs)
        lowerer = _ScopeLowerer(SimpleNamespace(model=self.model, facts=facts, pou_nodes={}),
                                self.settings, DEBUG_OPTIONS)
        lowerer.assign_names()
        lowerer.types = self.types
        lowerer.pou = pou
        lowerer.owner = scope.owner
        return checker, lowerer, facts, saved_facts, saved_diags

    def _finish(self, saved_facts, saved_diags, text: str) -> None:
        errors = self.checker.diags[saved_diags:]
        del self.checker.diags[saved_diags:]
        self.checker.facts = saved_facts
        bad = [d for d in errors if d.is_error]
        if bad:
            raise DebugError(_messages(bad, text))

    def compile_expression(self, scope: Scope, text: str) -> Compiled:
        return _internal_errors_as_debug_errors(self._compile_expression, scope, text)

    def compile_store(self, scope: Scope, target_text: str, value_text: str) -> CompiledStore:
        return _internal_errors_as_debug_errors(self._compile_store, scope, target_text, value_text)

    def _compile_expression(self, scope: Scope, text: str) -> Compiled:
        expr = self.parse(text)
        with self._lock:
            checker, lowerer, facts, saved_facts, saved_diags = self._session(scope)
            try:
                ty = checker.expr(expr)
            finally:
                checker.release()
                self._finish(saved_facts, saved_diags, text)
            if ty is None or isinstance(ty, t.VoidType):
                raise DebugError(f"{text.strip()!r} has no value")
            source = lowerer.expr(expr)
        return Compiled(text.strip(), _compile(source, "eval"), ty, scope.key())

    def compile_condition(self, scope: Scope, text: str) -> Compiled:
        compiled = self.compile_expression(scope, text)
        if not isinstance(compiled.type, t.BoolType):
            raise DebugError(f"a condition must be BOOL, not {compiled.type.name}")
        return compiled

    def _compile_store(self, scope: Scope, target_text: str, value_text: str) -> CompiledStore:
        target, value = self.parse(target_text), self.parse(value_text)
        if not isinstance(target, (n.Name, n.Member, n.Index, n.BitAccess)):
            raise DebugError(f"{target_text.strip()!r} is not a variable")
        statement = n.Assign(target, value, target.span)
        with self._lock:
            checker, lowerer, facts, saved_facts, saved_diags = self._session(scope)
            try:
                checker.statement(statement)
            finally:
                checker.release()
                self._finish(saved_facts, saved_diags, f"{target_text} := {value_text}")
            ty = facts.types.get(target.nid)
            if ty is None:
                raise DebugError(f"{target_text.strip()!r} cannot be assigned")
            value_source = lowerer.expr_as(value, ty)
            if isinstance(ty, (t.StructType, t.ArrayType)):
                value_source = f"_copy_value({value_source})"
            store_source = "\n".join(lowerer.store_code(target, "_value", ty))
            root = target
            while isinstance(root, (n.Member, n.Index, n.BitAccess)):
                root = root.base
            ref = facts.names.get(root.nid)
            local = ref is not None and ref.kind == "var"
            canonical = unparse(target, facts)
        return CompiledStore(target_text.strip(), _compile(value_source, "eval"), _compile(store_source, "exec"),
                             ty, local, canonical)

    # ---- running
    def namespace(self, vm, scope: Scope) -> dict[str, Any]:
        """Locals for evaluating compiled text in `scope` (globals are the VM's module namespace)."""
        view = self._views.get(id(vm))   # not a node: one view per VM object
        if view is None or view[0] is not vm:
            # program instances never change during a run: one view per VM
            programs = {var_attr(name): inst for name, inst, _ in vm.instances.values()}
            view = self._views[id(vm)] = (vm, GlobalsView(vm.globals, programs))   # not a node
        return {"self": scope.instance, "_f": scope.frame, "_r": scope.result, "_T": self.types, "_G": view[1]}

    def evaluate(self, vm, scope: Scope, compiled: Compiled) -> Any:
        return run_guarded(lambda: eval(compiled.code, vm.namespace, self.namespace(vm, scope)))

    def store(self, vm, scope: Scope, store: CompiledStore, value: Any) -> None:
        local_ns = self.namespace(vm, scope)
        local_ns["_value"] = value
        run_guarded(lambda: exec(store.store_code, vm.namespace, local_ns))

    def value(self, vm, scope: Scope, store: CompiledStore) -> Any:
        return run_guarded(lambda: eval(store.value_code, vm.namespace, self.namespace(vm, scope)))


def _internal_errors_as_debug_errors(fn, *args):
    """A checker or code-generator exception on debugger text is an stvm bug; the session goes on."""
    try:
        return fn(*args)
    except DebugError:
        raise
    except RecursionError:
        raise DebugError("the expression is nested too deeply for the debugger") from None
    except Exception as exc:  # noqa: BLE001 - reported to the user, never fatal to the session
        text = " := ".join(a for a in args[1:] if isinstance(a, str))
        raise DebugError(f"stvm cannot handle {_shown(text)} ({type(exc).__name__}: {_shown(str(exc), quote=False)}); "
                         f"this is an stvm bug") from exc


def run_guarded(fn):
    """Run debugger code; ST faults and instruction errors become DebugError."""
    try:
        return fn()
    except STFault as exc:
        raise DebugError(f"fault: {exc}") from None
    except FunctionError as exc:
        raise DebugError(f"instruction error: {exc}") from None
    except AttributeError as exc:
        if "'NoneType'" in str(exc):
            raise DebugError("an in-out is not bound yet (the block has not been called)") from None
        raise DebugError(f"cannot evaluate: {exc}") from None
    except RecursionError:
        raise DebugError("cannot evaluate: recursion too deep") from None
    except Exception as exc:  # noqa: BLE001 - runs inside the trace function too: never escape
        raise DebugError(f"cannot evaluate: {type(exc).__name__}: {exc}") from None


def unparse(e: n.Expr, facts: Facts | None = None) -> str:
    """Lower-case canonical text of an access path (`main.fb.arr[3].x`), for matching."""
    if isinstance(e, n.Name):
        return "\\".join(p.lower() for p in e.parts)
    if isinstance(e, n.Member):
        return f"{unparse(e.base, facts)}.{e.name.lower()}"
    if isinstance(e, n.BitAccess):
        return f"{unparse(e.base, facts)}.{e.bit}"
    if isinstance(e, n.Index):
        parts = []
        for ix in e.indices:
            value = facts.consts.get(ix.nid) if facts is not None else None
            parts.append(str(value) if isinstance(value, int) else unparse(ix, facts))
        return f"{unparse(e.base, facts)}[{','.join(parts)}]"
    if isinstance(e, n.IntLiteral):
        return str(e.value)
    return type(e).__name__.lower()


def _compile(source: str, mode: str) -> CodeType:
    return compile(source, EXPR_FILENAME, mode)


# What the debugger evaluates (watch, hover, console, conditions, set/force): a hostile or pasted
# 40 KB expression must give a short error, not a RecursionError reported as an stvm bug with
# the whole text (issue 34 item 11).
MAX_EXPRESSION_CHARS = 4096
MAX_EXPRESSION_DEPTH = 100
_MAX_MESSAGES = 3


def _tree_depth(node: object) -> int:
    """How deep a syntax tree is, walked with a stack (never recursively)."""
    deepest = 0
    stack = [(node, 1)]
    while stack:
        item, depth = stack.pop()
        if depth > deepest:
            deepest = depth
        for name in getattr(item, "__dataclass_fields__", ()):
            child = getattr(item, name, None)
            if isinstance(child, (list, tuple)):
                stack.extend((c, depth + 1) for c in child if hasattr(c, "__dataclass_fields__"))
            elif hasattr(child, "__dataclass_fields__") and name != "span":
                stack.append((child, depth + 1))
    return deepest


def _shown(text: str, limit: int = 80, quote: bool = True) -> str:
    """`text` for a message: control characters escaped, cut to `limit` characters."""
    text = "".join(c if c.isprintable() else f"\\x{ord(c):02x}" for c in text[:limit + 1])
    text = text if len(text) <= limit else text[:limit] + "…"
    return repr(text) if quote else text


def _messages(diags, text: str) -> str:
    out = []
    for d in diags:
        col = d.span.column if d.span.file == EXPR_FILENAME and d.span.column > 0 else 0
        out.append(d.message + (f" (column {col})" if col and len(text.strip()) > 20 else ""))
    unique = list(dict.fromkeys(out))
    more = len(unique) - _MAX_MESSAGES
    return "; ".join(unique[:_MAX_MESSAGES]) + (f"; and {more} more error(s)" if more > 0 else "")
