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
from stvm.dialects import allows
from stvm.semantics.model import (EXTERNAL, GLOBAL, IN_OUT, INPUT, LOCAL, OUTPUT, POUInfo,
                                  PropertyInfo, TaskInfo, Variable)
from stvm.settings import Dialect
from stvm.source import is_stdlib_file
from stvm.syntax.pragmas import has_attribute
from stvm.syntax.walk import calls_in


@dataclass
class Analysis:
    model: ProjectModel
    facts: Facts
    units: list[n.CompilationUnit]
    pou_nodes: dict[str, n.POU]
    diagnostics: list[Diagnostic]
    type_inits: dict[str, dict[str, object]]   # struct qualname key → field key → initial value
    method_nodes: dict[str, n.Method] = field(default_factory=dict)   # METHOD/GET/SET key → node


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
        self.declare_all()
        self.link_oo()
        self.resolve_fb_instance_inits()
        self.resolve_fb_init_args()

    def run(self) -> Analysis:
        self.build_index()
        for key, pou in self.ctx.index.pou_nodes.items():
            info = self.ctx.pous[key]
            if info.native:
                if pou.body:
                    self.error(f"native POU '{pou.name}' must not have a body", pou.span, "E025")
                continue
            BodyChecker(self, info, pou).check()
            for method in self.members_of(info):
                BodyChecker(self, method, self.ctx.method_nodes[method.key], fb=info, fb_node=pou).check()
        # the depth check walks iteratively and runs first: the two checks after it recurse,
        # and a chain thousands deep must be a diagnostic naming it, not a RecursionError
        if self.check_nesting_depth():
            self.check_containment()
            self.check_recursion()
            self.check_method_recursion()
        tasks, defaults = self.check_configuration()
        model = ProjectModel(self.ctx.pous, self.ctx.globals, tasks, defaults, self.ctx.structs, self.ctx.enums)
        return Analysis(model, self.ctx.facts, self.ctx.units, dict(self.ctx.index.pou_nodes), self.ctx.diags,
                        self.ctx.type_inits, self.ctx.method_nodes)

    def declare_all(self) -> None:
        """Declare the globals, types and POU signatures the index holds."""
        # Order matters only inside this method: global constants of elementary types first (array
        # bounds and STRING sizes may use them), then types (enumerators must be known before
        # initial values resolve), then the other globals, then POU signatures.
        blocks = []
        for unit in self.ctx.units:
            blocks += [(g.block, g.namespace) for g in unit.globals]
            for conf in unit.configurations:
                blocks += [(b, ()) for b in conf.globals]
                for res in conf.resources:
                    blocks += [(b, ()) for b in res.globals]
        for block, namespace in blocks:
            if block.constant:
                self.declare_globals(block, namespace, elementary_only=True)
        for key, decl in self.ctx.index.type_decls.items():
            self.types.resolve_declared_type(key)
        for block, namespace in blocks:
            self.declare_globals(block, namespace, elementary_only=False if block.constant else None)
        for key, pou in self.ctx.index.pou_nodes.items():
            self.ctx.pous[key] = self.declare_pou(pou)

    def declare_globals(self, block: n.VarBlock, namespace: tuple[str, ...], elementary_only: bool | None = None) -> None:
        """Declare a VAR_GLOBAL block. `elementary_only` True: only its elementary-typed entries
        (the early pass for constants); False: only the others; None: all."""
        if block.kind != GLOBAL and elementary_only is not True:
            self.error(f"only VAR_GLOBAL is allowed outside a POU, not {block.kind}", block.span, "E012")
        for decl in block.decls:
            elementary = isinstance(decl.type_spec, n.NamedTypeSpec) and len(decl.type_spec.parts) == 1 \
                and decl.type_spec.parts[0].upper() in t.ELEMENTARY
            if elementary_only is not None and elementary != elementary_only:
                continue
            vtype = self.types.resolve_type_spec(decl.type_spec, namespace)
            for name, span in decl.names:
                self.indexer.check_identifier(name, span)
                if name.lower() in self.ctx.globals:
                    self.error(f"duplicate declaration of global '{name}'", span, "E010")
                    continue
                var = Variable(name, GLOBAL, vtype or t.DINT, block.constant, span)
                if decl.init is None:
                    var.init = self.types.alias_init(decl.type_spec, namespace)
                if vtype is not None and decl.init is not None:
                    var.init = self.constants.initial_value(decl.init, vtype, namespace, None)
                elif block.constant and decl.init is None:
                    self.error(f"constant '{name}' needs an initial value", span, "E013")
                self.ctx.globals[name.lower()] = var
                self.ctx.global_nodes[name.lower()] = decl
                if decl.fb_args is not None:
                    self.ctx.fb_init_arg_decls.append((var, decl, vtype, namespace, None))

    def declare_pou(self, pou: n.POU) -> POUInfo:
        qual = "\\".join(pou.namespace + (pou.name,))
        words = " ".join(pou.pragmas).lower().split()
        native = "native" in words
        if native and not _is_stdlib(pou.span.file):
            # binding to Python implementations is the stdlib's privilege, not user code's
            self.error("{native} is reserved for the stvm standard library", pou.span, "E025")
            native = False
        info = POUInfo(pou.name, qual, pou.kind, None, native=native, generic="generic" in words,
                       variadic="variadic" in words, typed="typed" in words, file=pou.span.file,
                       span=pou.span)
        for word in words:
            if word.startswith("quiet:") and native:
                info.quiet_pin = word[len("quiet:"):]
            if word.startswith("alias:") or (word.count("=") == 1 and "alias" in words):
                alias, _, pin = word.split(":", 1)[-1].partition("=")
                if alias and pin:
                    info.aliases[alias] = pin
        self.indexer.check_identifier(pou.name, pou.span)
        mods = set(pou.modifiers)
        info.abstract, info.final = "ABSTRACT" in mods, "FINAL" in mods
        if mods and pou.kind != "FUNCTION_BLOCK":
            self.error(f"{', '.join(sorted(mods))} is only allowed on a FUNCTION_BLOCK, METHOD or PROPERTY",
                       pou.name_span if pou.name_span.line else pou.span, "E060")
        if info.abstract and info.final:
            self.error(f"function block '{pou.name}' cannot be both ABSTRACT and FINAL", pou.span, "E060")
        self.ctx.declaring = info   # its constants may size its arrays and strings (const_value)
        if pou.kind == "INTERFACE":
            info.return_type = None
            self.declare_members(pou, info)
            self.ctx.declaring = None
            return info
        if pou.kind == "FUNCTION":
            if pou.return_type is None:
                # TwinCAT/CODESYS: a function without a result, called as a statement (like a METHOD
                # without one: return_type None, so its name is no result variable)
                if not allows(self.ctx.settings.dialect, "void_function"):
                    self.error(f"function '{pou.name}' needs a return type", pou.span, "E014")
                    info.return_type = t.VOID
            else:
                info.return_type = self.types.resolve_type_spec(pou.return_type, pou.namespace, allow_generic=native) or t.DINT
        elif pou.return_type is not None:
            self.error(f"a {pou.kind} has no return type", pou.span, "E014")
        self.declare_variables(pou, info, pou.namespace, native)
        self.ctx.declaring = None
        if pou.kind == "FUNCTION" and (pou.methods or pou.properties):
            what = pou.methods[0] if pou.methods else pou.properties[0]
            self.error("a FUNCTION has no methods or properties; declare them in a FUNCTION_BLOCK",
                       what.span, "E061")
        else:
            self.declare_members(pou, info)
        return info

    def declare_variables(self, pou, info: POUInfo, namespace: tuple[str, ...], native: bool = False) -> None:
        """Declare the variable blocks of a POU or METHOD (`pou`: its node) into `info`."""
        early = self.declare_local_constants(pou, info, namespace)
        function_like = info.kind in ("FUNCTION", "METHOD") and info.return_type is not None
        for block in pou.var_blocks:
            kind = block.kind
            if kind == "VAR_STAT":
                kind = LOCAL
            if kind == GLOBAL:
                self.error("VAR_GLOBAL is not allowed inside a POU; declare globals at top level", block.span, "E012")
                continue
            for decl in block.decls:
                if decl.nid in early:
                    continue
                spec = decl.type_spec
                if not native and kind == INPUT and isinstance(spec, n.NamedTypeSpec) \
                        and [p.upper() for p in spec.parts] == ["ANY"] and allows(self.ctx.settings.dialect, "any_input"):
                    # TwinCAT/CODESYS: an ANY input is the descriptor __SYSTEM.AnyType (docs/memory_model.md)
                    spec = n.NamedTypeSpec(("__SYSTEM", "AnyType"), False, spec.span)
                vtype = self.types.resolve_type_spec(spec, namespace, allow_generic=native,
                                               allow_open_array=kind in (IN_OUT, INPUT))
                for name, span in decl.names:
                    self.indexer.check_identifier(name, span)
                    key = name.lower()
                    if key in info.variables:
                        self.error(f"duplicate declaration of '{name}' in {pou.name}", span, "E010")
                        continue
                    if function_like and key == pou.name.lower():
                        self.error(f"'{name}' is the {info.kind.lower()}'s own name", span, "E010")
                        continue
                    # TwinCAT/CODESYS: a VAR_INPUT CONSTANT without initial value is an input fixed
                    # where the instance is declared or called, 0 by default (stvm/dialects.py
                    # `input_constant`): an input, not a compile-time constant
                    input_constant = (block.constant and kind == INPUT and decl.init is None
                                      and allows(self.ctx.settings.dialect, "input_constant"))
                    var = Variable(name, kind, vtype or t.DINT, block.constant and not input_constant, span)
                    var.instance_path = bool(decl.pragmas) and isinstance(vtype, t.StringType) \
                        and has_attribute(decl.pragmas, "instance-path")
                    if decl.init is None and kind not in (IN_OUT, EXTERNAL):
                        var.init = self.types.alias_init(decl.type_spec, namespace)
                    # VAR_IN_OUT CONSTANT (CODESYS/TwinCAT): an in-out the POU may not write; its
                    # value is the caller's
                    if block.constant and decl.init is None and kind not in (EXTERNAL, IN_OUT) and not input_constant:
                        self.error(f"constant '{name}' needs an initial value", span, "E013")
                    info.variables[key] = var
                    if decl.fb_args is not None:
                        self.ctx.fb_init_arg_decls.append((var, decl, vtype, namespace, info))
                    if vtype is not None and decl.init is not None:
                        if kind == IN_OUT:
                            self.error(f"VAR_IN_OUT '{name}' cannot have an initial value", span, "E013")
                        else:
                            var.init = self.constants.initial_value(decl.init, vtype, namespace, info)
        if early:   # back to declaration order (positional parameters, formatting, traces)
            order = [name.lower() for block in pou.var_blocks for decl in block.decls for name, _ in decl.names]
            rank = {key: i for i, key in reversed(list(enumerate(order)))}
            info.variables = dict(sorted(info.variables.items(), key=lambda kv: rank.get(kv[0], len(order))))
        if any(block.kind == "VAR_STAT" for block in pou.var_blocks):
            self.hoist_static_variables(pou, info)

    def declare_members(self, pou: n.POU, info: POUInfo) -> None:
        """The METHODs and PROPERTYs of an FB, PROGRAM or INTERFACE (signatures; bodies are
        checked with the POU's)."""
        for m in pou.methods:
            method = self.declare_method(m, info, pou)
            if m.name.lower() in info.methods or m.name.lower() in info.properties:
                self.error(f"duplicate method '{m.name}' in {pou.name}", m.name_span, "E010")
                continue
            if m.name.lower() in info.variables:
                self.error(f"'{m.name}' is both a variable and a method of {pou.name}", m.name_span, "E010")
                continue
            info.methods[m.name.lower()] = method
        merged: dict[str, list[n.Property]] = {}
        for prop in pou.properties:   # a GET and a SET may come as two PROPERTY blocks of one name
            merged.setdefault(prop.name.lower(), []).append(prop)
        for key, props in merged.items():
            prop = props[0]
            getters = [p.getter for p in props if p.getter is not None]
            setters = [p.setter for p in props if p.setter is not None]
            if len(getters) > 1 or len(setters) > 1 or (len(props) > 1 and any(
                    self.types.resolve_type_spec(p.type_spec, pou.namespace) != self.types.resolve_type_spec(prop.type_spec, pou.namespace)
                    for p in props[1:])):
                self.error(f"duplicate property '{prop.name}' in {pou.name}", props[-1].name_span, "E010")
                continue
            if key in info.methods or key in info.variables:
                self.error(f"'{prop.name}' is declared twice in {pou.name}", prop.name_span, "E010")
                continue
            self.indexer.check_identifier(prop.name, prop.name_span)
            ptype = self.types.resolve_type_spec(prop.type_spec, pou.namespace) or t.DINT
            access, abstract, final = self.member_modifiers(prop.modifiers, prop.name_span, "property")
            if not getters and not setters:
                self.error(f"property '{prop.name}' needs a GET or a SET", prop.name_span, "E062")
            accessors = {}
            for kind, acc in (("GET", getters[0] if getters else None), ("SET", setters[0] if setters else None)):
                if acc is None:
                    accessors[kind] = None
                    continue
                m = n.Method(prop.name, prop.modifiers, prop.type_spec if kind == "GET" else None,
                             prop.var_blocks + acc.var_blocks, acc.body, (), acc.span, prop.name_span)
                method = self.declare_method(m, info, pou, accessor=kind, prop_type=ptype)
                accessors[kind] = method
            info.properties[key] = PropertyInfo(prop.name, ptype, accessors["GET"], accessors["SET"],
                                                info.key, access, prop.name_span)

    def member_modifiers(self, modifiers: tuple[str, ...], span: n.Span, what: str) -> tuple[str, bool, bool]:
        access = [m for m in modifiers if m in ("PUBLIC", "PRIVATE", "PROTECTED", "INTERNAL")]
        if len(access) > 1:
            self.error(f"a {what} has one access specifier, not {' and '.join(access)}", span, "E060")
        abstract, final = "ABSTRACT" in modifiers, "FINAL" in modifiers
        if abstract and final:
            self.error(f"a {what} cannot be both ABSTRACT and FINAL", span, "E060")
        return (access[0] if access else "PUBLIC"), abstract, final

    def hoist_static_variables(self, pou, info: POUInfo) -> None:
        """CODESYS VAR_STAT (of a FUNCTION, FB, PROGRAM or METHOD): one variable for the POU,
        kept across calls and shared by every instance of an FB, i.e. a global under a name no
        ST declaration takes (`FB_Axis__Move__calls`); the POU's name resolves to it
        (`stat_vars`, body.py `static_variable`). A VAR_STAT CONSTANT stays a local constant."""
        static = [name.lower() for block in pou.var_blocks if block.kind == "VAR_STAT" and not block.constant
                  for decl in block.decls for name, _ in decl.names]
        for key in static:
            var = info.variables.get(key)
            if var is None or var.section != LOCAL:
                continue    # a duplicate, already reported
            # a library's POU is named `Lib\POU` (TcUnit's TEST_FINISHED_NAMED): no backslash in the global
            owner = info.qualname.replace(".", "__").replace("\\", "__")
            hidden = Variable(f"{owner}__{var.name}", GLOBAL, var.type, False, var.span)
            hidden.init = var.init
            self.ctx.globals[hidden.key] = hidden
            del info.variables[key]
            info.stat_vars[key] = hidden.key
            self.ctx.any_static = True

    def check_lifecycle_method(self, m: n.Method, info: POUInfo) -> None:
        """CODESYS/TwinCAT FB_init(bInitRetains, bInCopyCode : BOOL) and FB_exit(bInCopyCode : BOOL)
        (compiler error C0119 where they lack them). stvm calls FB_init itself with the other
        inputs' initial values, so it takes inputs only."""
        needed = ("bInitRetains", "bInCopyCode") if m.name.lower() == "fb_init" else ("bInCopyCode",)
        for name in needed:
            var = info.variables.get(name.lower())
            if var is None or var.section != INPUT or not isinstance(var.type, t.BoolType):
                self.error(f"{m.name} needs the input{'s' if len(needed) > 1 else ''} {' and '.join(needed)} "
                           f"of type BOOL", m.name_span, "E063")
                return
        extra = next((v for v in info.variables.values() if v.section in (OUTPUT, IN_OUT)), None)
        if extra is not None:
            self.error(f"{m.name} takes inputs only (stvm calls it at instance creation), not "
                       f"{extra.section} '{extra.name}'", extra.span, "E063")

    def check_call_after_init(self, m: n.Method, info: POUInfo, pou: n.POU) -> None:
        """CODESYS `{attribute 'call_after_init'}` on a METHOD of an FB: stvm calls it once for every
        instance, after the FB_init methods (runtime/vm.py `run_fb_inits`), so it takes no
        inputs, outputs or in-outs."""
        if pou.kind != "FUNCTION_BLOCK":
            self.error("{attribute 'call_after_init'} is for a METHOD of a FUNCTION_BLOCK", m.name_span, "E063")
            return
        if m.name.lower() in ("fb_init", "fb_exit", "fb_reinit"):
            self.error(f"{{attribute 'call_after_init'}} cannot mark {m.name}", m.name_span, "E063")
            return
        param = next((v for v in info.variables.values() if v.section in (INPUT, OUTPUT, IN_OUT)), None)
        if param is not None:
            self.error(f"a call_after_init method takes no parameters (stvm calls it at instance creation), "
                       f"not {param.section} '{param.name}'", param.span, "E063")
            return
        info.call_after_init = True

    def declare_method(self, m: n.Method, owner: POUInfo, pou: n.POU, accessor: str = "",
                       prop_type: t.Type | None = None) -> POUInfo:
        qual = owner.qualname + "." + (f"__{accessor.lower()}_" if accessor else "") + m.name
        info = POUInfo(m.name, qual, "METHOD", None, file=m.span.file, span=m.span)
        info.owner = owner.key
        self.ctx.method_nodes[info.key] = m
        info.access, info.abstract, info.final = self.member_modifiers(m.modifiers, m.name_span, "method")
        if not accessor:
            self.indexer.check_identifier(m.name, m.name_span)
        outer, self.ctx.declaring = self.ctx.declaring, info
        if accessor == "GET":
            info.return_type = prop_type
        elif m.return_type is not None:
            info.return_type = self.types.resolve_type_spec(m.return_type, pou.namespace) or t.DINT
        if accessor == "SET":   # the property's name is the value being set
            info.variables[m.name.lower()] = Variable(m.name, INPUT, prop_type or t.DINT, False, m.name_span)
        self.declare_variables(m, info, pou.namespace)
        self.ctx.declaring = outer
        for block in m.var_blocks:
            if block.kind == "VAR_STAT" and pou.kind == "INTERFACE":
                self.error("an interface method declares only inputs, outputs and in-outs, not VAR_STAT",
                           block.span, "E063")
            elif block.kind == "VAR_INST" and pou.kind not in ("FUNCTION_BLOCK", "PROGRAM"):
                self.error("VAR_INST is only allowed in a method of a FUNCTION_BLOCK or PROGRAM", block.span, "E012")
        for key, var in list(info.variables.items()):
            if var.section == "VAR_INST" and pou.kind in ("FUNCTION_BLOCK", "PROGRAM"):
                # kept in the instance under a name no ST declaration can take (`Method__x`)
                hidden = Variable(f"{m.name}__{var.name}", LOCAL, var.type, var.constant, var.span)
                hidden.init = var.init
                owner.variables[hidden.key] = hidden
                info.inst_vars[key] = hidden.key
        if not accessor and m.name.lower() in ("fb_init", "fb_exit") and pou.kind == "FUNCTION_BLOCK":
            self.check_lifecycle_method(m, info)
        if not accessor and has_attribute(m.pragmas, "call_after_init"):
            self.check_call_after_init(m, info, pou)
        if pou.kind == "INTERFACE":
            if m.body:
                self.error(f"method '{m.name}' of interface {pou.name} cannot have statements", m.body[0].span, "E063")
            if any(v.section not in (INPUT, OUTPUT, IN_OUT) for v in info.variables.values()):
                bad = next(v for v in info.variables.values() if v.section not in (INPUT, OUTPUT, IN_OUT))
                self.error(f"an interface method declares only inputs, outputs and in-outs, not {bad.section}",
                           bad.span, "E063")
            info.abstract = True
        elif info.abstract and m.body:
            self.error(f"ABSTRACT method '{m.name}' cannot have statements", m.body[0].span, "E063")
        return info

    def members_of(self, info: POUInfo) -> list[POUInfo]:
        """The METHODs and property accessors an FB, PROGRAM or INTERFACE declares itself."""
        out = list(info.methods.values())
        for prop in info.properties.values():
            out += [m for m in (prop.getter, prop.setter) if m is not None]
        return out

    def link_oo(self) -> None:
        """Resolve EXTENDS and IMPLEMENTS, report cycles, inherit the base's variables."""
        for key, pou in self.ctx.index.pou_nodes.items():
            info = self.ctx.pous[key]
            if pou.extends:
                if pou.kind == "INTERFACE":
                    info.interfaces = tuple(k for k in (self.interface_key(name, pou) for name in pou.extends) if k)
                elif pou.kind != "FUNCTION_BLOCK":
                    self.error(f"a {pou.kind} cannot EXTEND; only a FUNCTION_BLOCK or INTERFACE can",
                               pou.extends[0].span, "E064")
                elif len(pou.extends) > 1:
                    self.error("a function block EXTENDS one base function block", pou.extends[1].span, "E064")
                else:
                    base = pou.extends[0]
                    bkey = self.ctx.index.lookup_pou_key(base.parts, pou.namespace)
                    binfo = self.ctx.pous.get(bkey) if bkey else None
                    if binfo is None or binfo.kind != "FUNCTION_BLOCK" or binfo.native:
                        what = "unknown function block" if binfo is None else f"'{base.text}' is not a function block; cannot extend"
                        self.error(f"{what} '{base.text}'" if binfo is None else what, base.span, "E064")
                    elif binfo.final:
                        self.error(f"function block '{binfo.name}' is FINAL and cannot be extended", base.span, "E064")
                    else:
                        info.base = bkey
            if pou.implements:
                if pou.kind not in ("FUNCTION_BLOCK",):
                    self.error(f"a {pou.kind} cannot IMPLEMENT an interface", pou.implements[0].span, "E064")
                else:
                    info.interfaces = tuple(k for k in (self.interface_key(name, pou) for name in pou.implements) if k)
        # cycles: a chain of bases that comes back
        for key, info in self.ctx.pous.items():
            if info.kind == "FUNCTION_BLOCK" and info.base:
                chain, cur = [key], info.base
                while cur is not None and cur not in chain:
                    chain.append(cur)
                    cur = self.ctx.pous[cur].base
                if cur == key:
                    names = " -> ".join(self.ctx.pous[k].name for k in chain + [key])
                    self.error(f"cycle in EXTENDS: {names}", self.ctx.index.pou_nodes[key].extends[0].span, "E065")
                    info.base = None
            if info.kind == "INTERFACE" and info.interfaces:
                seen: set[str] = set()
                stack = list(info.interfaces)
                while stack:
                    cur = stack.pop()
                    if cur == key:
                        self.error(f"cycle in INTERFACE EXTENDS through {info.name}",
                                   self.ctx.index.pou_nodes[key].extends[0].span, "E065")
                        info.interfaces = ()
                        break
                    if cur not in seen:
                        seen.add(cur)
                        stack.extend(self.ctx.pous[cur].interfaces)
        merged: set[str] = set()

        def inherit(key: str) -> None:
            if key in merged:
                return
            merged.add(key)
            info = self.ctx.pous[key]
            if info.base is None:
                return
            inherit(info.base)
            base = self.ctx.pous[info.base]
            variables = dict(base.variables)
            for vkey, var in info.variables.items():
                if vkey in variables:
                    self.error(f"'{var.name}' is already declared in the base function block {base.name}",
                               var.span, "E010")
                    continue
                variables[vkey] = var
            info.inherited = len(base.variables)
            info.variables = variables

        for key, info in list(self.ctx.pous.items()):
            if info.kind == "FUNCTION_BLOCK":
                inherit(key)
        del inherit   # a closure calling itself is a cycle: it would keep the checker alive
        for key, info in self.ctx.pous.items():
            for method in info.methods.values():
                if method.name.lower() in info.variables and info.inherited:
                    self.error(f"'{method.name}' is a variable of the base function block; a method cannot "
                               f"have its name", method.span, "E010")
        self.check_oo_rules()

    def interface_key(self, name: n.Name, pou: n.POU) -> str | None:
        key = self.ctx.index.lookup_pou_key(name.parts, pou.namespace)
        if key is None or self.ctx.pous[key].kind != "INTERFACE":
            self.error(f"unknown interface '{name.text}'" if key is None else f"'{name.text}' is not an interface",
                       name.span, "E064")
            return None
        return key

    def base_chain(self, key: str) -> list[POUInfo]:
        """The FB and its bases, the FB first."""
        out = []
        cur: str | None = key
        while cur is not None and cur in self.ctx.pous and len(out) < 1000:
            out.append(self.ctx.pous[cur])
            cur = self.ctx.pous[cur].base
        return out

    def find_method(self, key: str, name: str) -> POUInfo | None:
        """The method `name` of FB/PROGRAM `key` (own or inherited) or of interface `key` (own or
        from the interfaces it extends)."""
        low = name.lower()
        info = self.ctx.pous.get(key)
        if info is None:
            return None
        if info.kind == "INTERFACE":
            for itf in self.interface_closure(key):
                m = self.ctx.pous[itf].methods.get(low)
                if m is not None:
                    return m
            return None
        for fb in self.base_chain(key):
            if low in fb.methods:
                return fb.methods[low]
        return None

    def find_property(self, key: str, name: str) -> PropertyInfo | None:
        low = name.lower()
        info = self.ctx.pous.get(key)
        if info is None:
            return None
        chain = [self.ctx.pous[k] for k in self.interface_closure(key)] if info.kind == "INTERFACE" else self.base_chain(key)
        for fb in chain:
            if low in fb.properties:
                return fb.properties[low]
        return None

    def interface_closure(self, key: str) -> list[str]:
        """An interface and every interface it extends, itself first."""
        out, stack = [], [key]
        while stack:
            cur = stack.pop(0)
            if cur not in out and cur in self.ctx.pous:
                out.append(cur)
                stack.extend(self.ctx.pous[cur].interfaces)
        return out

    def implemented_interfaces(self, key: str) -> set[str]:
        """Every interface an FB implements (itself or through its bases), with what they extend."""
        out: set[str] = set()
        for fb in self.base_chain(key):
            for itf in fb.interfaces:
                out.update(self.interface_closure(itf))
        return out

    def is_derived(self, key: str, base: str) -> bool:
        return any(fb.key == base for fb in self.base_chain(key))

    def check_oo_rules(self) -> None:
        """Overrides match, FINAL is not overridden, a concrete FB implements every ABSTRACT and
        interface method and property (IEC ed. 3 6.6.5.5-6.6.6)."""
        for key, info in self.ctx.pous.items():
            if info.kind != "FUNCTION_BLOCK":
                continue
            node = self.ctx.index.pou_nodes[key]
            bases = self.base_chain(key)[1:]
            for method in info.methods.values():
                for base in bases:
                    over = base.methods.get(method.name.lower())
                    if over is None:
                        continue
                    if over.final:
                        self.error(f"method '{method.name}' is FINAL in {base.name} and cannot be overridden",
                                   self.ctx.method_nodes[method.key].name_span, "E066")
                    elif over.access == "PRIVATE":
                        pass
                    else:
                        self.same_signature(method, over, f"{base.name}.{over.name}", "overrides")
                    break
            for prop in info.properties.values():
                for base in bases:
                    over = base.properties.get(prop.key)
                    if over is not None:
                        if over.type != prop.type:
                            self.error(f"property '{prop.name}' is {prop.type.name} but overrides "
                                       f"{base.name}.{over.name} of type {over.type.name}", prop.span, "E067")
                        break
            if info.abstract:
                continue
            # every method must have an implementation
            span = node.name_span if node.name_span.line else node.span
            reported: set[str] = set()
            for fb in reversed(self.base_chain(key)):
                for method in fb.methods.values():
                    impl = self.find_method(key, method.name)
                    if impl is not None and impl.abstract and method.name.lower() not in reported:
                        reported.add(method.name.lower())
                        if impl.owner == key:
                            self.error(f"ABSTRACT method '{impl.name}' needs an ABSTRACT function block; "
                                       f"declare FUNCTION_BLOCK ABSTRACT {info.name}",
                                       self.ctx.method_nodes[impl.key].name_span, "E068")
                            continue
                        self.error(f"function block '{info.name}' must implement the ABSTRACT method "
                                   f"'{method.name}' of {self.ctx.pous[impl.owner].name} (or be ABSTRACT)", span, "E068")
            for itf in sorted(self.implemented_interfaces(key)):
                iinfo = self.ctx.pous[itf]
                for method in iinfo.methods.values():
                    impl = self.find_method(key, method.name)
                    if impl is None:
                        self.error(f"function block '{info.name}' does not implement method '{method.name}' "
                                   f"of interface {iinfo.name}", span, "E068")
                    else:
                        if impl.access != "PUBLIC":
                            self.error(f"method '{impl.name}' implements interface {iinfo.name} and must be PUBLIC",
                                       self.ctx.method_nodes[impl.key].name_span, "E067")
                        self.same_signature(impl, method, f"{iinfo.name}.{method.name}", "implements")
                for prop in iinfo.properties.values():
                    impl_p = self.find_property(key, prop.name)
                    if impl_p is None:
                        self.error(f"function block '{info.name}' does not implement property '{prop.name}' "
                                   f"of interface {iinfo.name}", span, "E068")
                    elif impl_p.type != prop.type:
                        self.error(f"property '{impl_p.name}' is {impl_p.type.name}; interface {iinfo.name} "
                                   f"declares it {prop.type.name}", impl_p.span, "E067")
                    else:
                        for kind, want, have in (("GET", prop.getter, impl_p.getter), ("SET", prop.setter, impl_p.setter)):
                            if want is not None and have is None:
                                self.error(f"property '{impl_p.name}' needs a {kind} (interface {iinfo.name} "
                                           f"declares one)", impl_p.span, "E068")
        # an ABSTRACT function block has no instances (only references and interfaces to derived ones)
        seen_vars: set[int] = set()   # Variable objects (shared by a holder and its members), not nodes
        for key, info in self.ctx.pous.items():
            for holder in [info] + self.members_of(info):
                for var in holder.variables.values():
                    if id(var) in seen_vars:   # not a node
                        continue
                    seen_vars.add(id(var))   # not a node
                    ty = var.type
                    while isinstance(ty, t.ArrayType):
                        ty = ty.element
                    if isinstance(ty, t.FBType) and var.section not in (IN_OUT, EXTERNAL):
                        target = self.ctx.pous.get(ty.qualname.lower())
                        if target is not None and target.abstract:
                            self.error(f"cannot instantiate ABSTRACT function block '{target.name}' "
                                       f"('{var.name}'); declare an instance of a derived one", var.span, "E069")
        # an interface method redeclared in an extending interface must keep its signature
        for key, info in self.ctx.pous.items():
            if info.kind == "INTERFACE":
                for method in info.methods.values():
                    for other in self.interface_closure(key)[1:]:
                        over = self.ctx.pous[other].methods.get(method.name.lower())
                        if over is not None:
                            self.same_signature(method, over, f"{self.ctx.pous[other].name}.{over.name}", "redeclares")

    def same_signature(self, method: POUInfo, other: POUInfo, what: str, verb: str) -> None:
        """Report where `method` differs from `other` (return type, parameters in order)."""
        span = self.ctx.method_nodes[method.key].name_span if method.key in self.ctx.method_nodes else method.span

        def params(m: POUInfo) -> list[tuple[str, str, t.Type]]:
            return [(v.key, v.section, v.type) for v in m.variables.values() if v.section in (INPUT, OUTPUT, IN_OUT)]
        mine, theirs = params(method), params(other)
        if (method.return_type or t.VOID) != (other.return_type or t.VOID):
            have = method.return_type.name if method.return_type else "no result"
            want = other.return_type.name if other.return_type else "no result"
            self.error(f"method '{method.name}' returns {have} but {verb} {what}, which returns {want}", span, "E067")
            return
        if mine != theirs:
            def show(ps):
                return ", ".join(f"{sec.replace('VAR_', '')} {[v.name for v in (method.variables | other.variables).values() if v.key == k][0]} : {ty.name}"
                                 for k, sec, ty in ps) or "no parameters"
            self.error(f"signature of method '{method.name}' ({show(mine)}) does not match {what} "
                       f"({show(theirs)}), which it {verb}", span, "E067")

    def declare_local_constants(self, pou: n.POU, info: POUInfo, namespace: tuple[str, ...] = ()) -> set[int]:
        """Declare the POU's elementary VAR CONSTANT entries before anything else, so an array
        bound or STRING size may use a constant declared further down (IEC: declaration order
        does not matter). Returns the ids of the declarations done here."""
        done: set[int] = set()
        for block in pou.var_blocks:
            if not block.constant or block.kind not in (LOCAL, "VAR_STAT"):
                continue
            for decl in block.decls:
                spec = decl.type_spec
                if not (isinstance(spec, n.NamedTypeSpec) and len(spec.parts) == 1
                        and spec.parts[0].upper() in t.ELEMENTARY) or decl.init is None:
                    continue
                vtype = t.ELEMENTARY[spec.parts[0].upper()]
                fresh = [(name, span) for name, span in decl.names if name.lower() not in info.variables]
                if len(fresh) != len(decl.names):
                    continue   # a duplicate: the main pass reports it
                for name, span in fresh:
                    self.indexer.check_identifier(name, span)
                    var = Variable(name, LOCAL, vtype, True, span)
                    var.init = self.constants.initial_value(decl.init, vtype, namespace, info)
                    info.variables[name.lower()] = var
                done.add(decl.nid)
        return done

    def resolve_fb_instance_inits(self) -> None:
        while self.ctx.fb_instance_inits:
            out, init, ty, namespace, pou = self.ctx.fb_instance_inits.pop(0)
            info = self.ctx.pous.get(ty.qualname.lower())
            if info is None:
                continue
            for fname, finit in init.items:
                var = info.variables.get(fname.lower())
                if var is None or var.section == EXTERNAL:
                    self.error(f"function block {info.name} has no variable '{fname}' to initialise", finit.span, "E024")
                    continue
                if var.section in (IN_OUT, "VAR_TEMP") or var.constant:
                    what = {IN_OUT: "an in-out (a reference, bound at each call)",
                            "VAR_TEMP": "a VAR_TEMP (fresh at each call)"}.get(var.section, "a constant")
                    self.error(f"'{var.name}' of {info.name} is {what}: an instance initialiser cannot set it",
                               finit.span, "E024")
                    continue
                if fname.lower() in out:
                    self.error(f"'{var.name}' is initialised twice", finit.span, "E024")
                    continue
                out[var.key] = self.constants.initial_value(finit, var.type, namespace, pou)

    def resolve_fb_init_args(self) -> None:
        """CODESYS/TwinCAT `fb : F(1, nMax := 5)`: the inputs of F's FB_init (its own or its
        base's; bInitRetains and bInCopyCode excluded, stvm passes them), positional in
        declaration order or by name, each a constant. They become `Variable.fb_args`, which the
        lowering passes to every FB_init of the chain that has such an input."""
        while self.ctx.fb_init_arg_decls:
            var, decl, vtype, namespace, pou = self.ctx.fb_init_arg_decls.pop(0)
            span = decl.type_spec.span
            if vtype is None:
                continue   # an unknown type, already reported
            if not isinstance(vtype, t.FBType):
                self.error(f"arguments in parentheses after a type are FB_init arguments, but {vtype.name} "
                           "is not a function block", span, "E063")
                continue
            if var.section in (IN_OUT, EXTERNAL) or (var.section == INPUT and pou is not None
                                                     and pou.kind in ("FUNCTION", "METHOD")):
                self.error(f"FB_init arguments are given where an instance is declared, not on "
                           f"{var.section} '{var.name}'", span, "E063")
                continue
            fb = self.ctx.pous.get(vtype.qualname.lower())
            method = None
            while fb is not None and method is None:
                method = fb.methods.get("fb_init")
                fb = self.ctx.pous.get(fb.base) if fb.base else None
            if method is None:
                self.error(f"function block {vtype.name} has no FB_init method to take arguments", span, "E063")
                continue
            params = [v for v in method.params() if v.section == INPUT
                      and v.key not in ("binitretains", "bincopycode")]
            by_key = {v.key: v for v in params}
            values: dict = {}
            positional = 0
            named = False
            for arg in decl.fb_args:
                if arg.kind == "positional":
                    if named:
                        self.error("a positional FB_init argument after a named one", arg.span, "E063")
                        continue
                    if positional >= len(params):
                        self.error(f"too many FB_init arguments: {vtype.name}'s FB_init takes {len(params)} "
                                   f"besides bInitRetains and bInCopyCode", arg.span, "E063")
                        continue
                    target = params[positional]
                    positional += 1
                elif arg.kind == "input":
                    named = True
                    target = by_key.get((arg.name or "").lower())
                    if target is None:
                        self.error(f"{vtype.name}'s FB_init has no input '{arg.name}'"
                                   + (" (stvm passes bInitRetains and bInCopyCode itself)"
                                      if (arg.name or "").lower() in ("binitretains", "bincopycode") else ""),
                                   arg.span, "E063")
                        continue
                    if target.key in values:
                        self.error(f"FB_init input '{target.name}' is given twice", arg.span, "E063")
                        continue
                else:
                    self.error("FB_init takes inputs only: no '=>' in a declaration", arg.span, "E063")
                    continue
                value = self.constants.const_value(arg.value, namespace, pou)
                if value is NOT_CONST:
                    sibling = self.constants.sibling_instance(arg.value, target.type, pou, before=var.key)
                    if sibling is not None:
                        values[target.key] = sibling
                        continue
                    self.error("an FB_init argument in a declaration must be a constant expression",
                               arg.value.span, "E063")
                    continue
                value = self.constants.convert_constant(value, target.type, arg.value.span, arg.value)
                if value is not None:
                    values[target.key] = value
            if 0 < positional < len(params) and not named:
                self.error(f"{positional} FB_init argument{'s' if positional > 1 else ''} for "
                           f"{len(params)} inputs of {vtype.name}'s FB_init: give all of them, or name them",
                           span, "E063")
            var.fb_args = values

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
                out = []
                for fdecl in decl.body.fields:
                    if isinstance(fdecl.type_spec, (n.NamedTypeSpec, n.ArrayTypeSpec)):
                        spec = fdecl.type_spec
                        while isinstance(spec, n.ArrayTypeSpec):
                            spec = spec.element
                        if isinstance(spec, n.NamedTypeSpec):
                            fkey = self.ctx.index.lookup_type_key(spec.parts, spec.rooted, decl.namespace) \
                                or self.ctx.index.lookup_pou_key(spec.parts, decl.namespace)
                            if fkey is not None:
                                out += [(name, t.StructType(fkey, fkey)) for name, _ in fdecl.names]
                return out
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
            for method in self.members_of(info):
                node = self.ctx.method_nodes.get(method.key)
                if node is None:
                    continue
                calls = (self.ctx.facts.calls.get(call.nid) for call in self._calls_of(method.key, node))
                graph[method.key] = {call.pou.key for call in calls
                                     if call is not None and call.pou.kind == "METHOD" and call.oo != "itf"}
        if not any(graph.values()):
            return
        methods = {m.key: m for info in self.ctx.pous.values() for m in self.members_of(info)}
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


def analyze(units: list[n.CompilationUnit], settings: SysmacSettings = DEFAULT_SETTINGS,
            natives: Mapping[str, Any] | None = None) -> Analysis:
    """Check all units together; returns the model, per-node facts and every diagnostic.

    `natives`: the stdlib's native functions (stvm.stdlib.NATIVE_FUNCTIONS), for the result types
    of generic ones (SHL, MUX, TRUNC, …); without it their result is the common input type."""
    return Checker(units, settings, natives).run()


def _is_stdlib(file: str) -> bool:
    return is_stdlib_file(file)


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
