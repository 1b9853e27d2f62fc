"""Pass 3 of the checker: declarations (docs/architecture.md, "Checker passes").

`DeclarationPass` declares what the index holds, in the order constants need: elementary global
constants, then every TYPE, then the other globals, then each POU's signature (its variables,
METHODs and PROPERTYs), with the rules a declaration must follow (duplicates, constants without a
value, VAR_STAT hoisted to a hidden global, FB_init/FB_exit signatures).
"""

from __future__ import annotations


from stvm.dialects import allows
from stvm.semantics import types as t
from stvm.semantics.context import CheckContext, Pass
from stvm.semantics.model import (EXTERNAL, GLOBAL, IN_OUT, INPUT, LOCAL, OUTPUT, POUInfo,
                                  PropertyInfo, Variable)
from stvm.source import is_stdlib_file
from stvm.syntax import nodes as n
from stvm.syntax.pragmas import has_attribute


def _is_stdlib(file: str) -> bool:
    return is_stdlib_file(file)


class DeclarationPass(Pass):
    """Globals, TYPEs and POU signatures into `ctx` (module docstring)."""

    def __init__(self, ctx: CheckContext, indexer, types, constants) -> None:
        super().__init__(ctx)
        self.indexer = indexer       # index.Indexer
        self.types = types           # resolve.TypeResolver
        self.constants = constants   # constants.ConstantEvaluator

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
