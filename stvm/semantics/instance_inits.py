"""Pass 3 of the checker, once every POU is declared: instance initialisers
(docs/architecture.md, "Checker passes").

`fb : F := (x := 1)` and `fb : F(1, 2)` name F's variables and F's FB_init inputs, which exist only
once every POU is declared: the declarations queue them (`ctx.fb_instance_inits`,
`ctx.fb_init_arg_decls`) and `InstanceInits` resolves the queues in declaration order.
"""

from __future__ import annotations


from stvm.semantics import types as t
from stvm.semantics.context import CheckContext, Pass
from stvm.semantics.facts import NOT_CONST
from stvm.semantics.model import (EXTERNAL, IN_OUT, INPUT)


class InstanceInits(Pass):
    """The queued instance initialisers and FB_init arguments (module docstring)."""

    def __init__(self, ctx: CheckContext, constants) -> None:
        super().__init__(ctx)
        self.constants = constants   # constants.ConstantEvaluator

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
