"""The lowering's analysis pass: what each POU's code will need, decided before any code is written.

As CPython's symtable runs before its compiler, `plan_project` reads the checked project once and
returns a `ProjectPlan`: per POU (and METHOD / property accessor) a `PouPlan` with the variables it
uses and assigns, the ones passed by reference, and the ones a call keeps in Python locals; for the
whole project, keyed by stable node ids (`Node.nid`), the statements whose FUNCTION errors or
array-index errors are caught, the FOR loops that become a Python `range` (with their step, start,
type and hoisted bounds checks), the FB calls written into the caller or called straight through
their native implementation, and the ARRAY[*] arguments that keep their `ArrayRef`.

The generators (`gen_pou`, `gen_stmt`, `gen_expr`) only read the plan. Each optimisation that
decides *whether* something is done is a named function here that consults its `LowerOptions`
switch; the ones that only change *how* an expression is written (`ring_chain`,
`no_wrap_in_range`, `inline_struct_assign`, `inline_input_copy`) stay with their generator.

The checker's facts (`Analysis.facts`) and what this pass adds are both keyed by `node.nid`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping

from stvm.lower.hot_uses import CHILD_FIELDS, child_fields, hot_uses
from stvm.lower.options import LowerOptions
from stvm.semantics import types as t
from stvm.semantics.facts import CallInfo
from stvm.semantics.model import EXTERNAL, GLOBAL, IN_OUT, INPUT, LOCAL, OUTPUT, TEMP, POUInfo, Variable
from stvm.settings import ArrayOob, ForEndEval, OpenArrayBounds
from stvm.syntax import nodes as n
from stvm.syntax.walk import LOOP_WEIGHT, root_name, walk


@dataclass(frozen=True)
class RangeFor:
    """A FOR written as `for … in range()`: `range_for_ok` holds for it."""
    key: str                                   # the loop variable (lower case)
    step: int
    start: int | None                          # the start, when a constant
    var_type: t.IntType
    hoisted: tuple[tuple[int, int, int], ...]  # (offset, lo, hi) of the accesses checked once
    # constant start and end inside the variable's type, else None: the endless-loop guard and the
    # hoisted bounds test are then decided while lowering, and only the code that can run is written
    bounds: tuple[int, int] | None = None
    # with `bounds` and `hoisted`: whether every hoisted access stays inside its array (the one
    # copy of the loop written is the unchecked one); None when the test runs at run time
    fits: bool | None = None


@dataclass(frozen=True)
class ArrayRefReuse:
    """`reuse_array_refs`: an ARRAY[*] argument that is a fixed array of the caller (`base`), from
    element `start` on, seen with lower bound `lo`. The generator still requires the code of `base`
    to be a plain variable path (it is evaluated twice)."""
    base: n.Expr
    start: int
    lo: int


@dataclass(frozen=True)
class HeldDeref:
    """`hold_derefs_in_loops`: a loop during which the scalar target of the reference `ref` (a
    Python local never assigned in the loop) is kept in a Python local; `written`: the loop stores
    through it (the local is written back after the loop)."""
    ref: Variable
    written: bool
    # objects whose scalar fields the loop reads or writes (`p`, `p.q`, `rp^`) and arrays whose
    # elements it reads or writes: the held copy of the loop runs only when `ref` refers to none
    # of those fields and elements
    bases: tuple[n.Expr, ...] = ()
    arrays: tuple[n.Name, ...] = ()


@dataclass(frozen=True)
class PouPlan:
    """What the code of one call body (FB/PROGRAM `__call__`, FUNCTION, METHOD, accessor) needs."""
    key: str
    uses: Mapping[str, int]            # single-part names → uses in the body (loops weighted)
    assigned: frozenset[str]           # variables the body assigns (root names of targets)
    by_reference: frozenset[str]       # variables something may read or write through a reference
    cached: Mapping[str, Variable]     # variables a call keeps in Python locals
    frameless: bool = False            # a METHOD whose variables are all Python locals


@dataclass(frozen=True)
class ProjectPlan:
    pous: Mapping[str, PouPlan] = field(default_factory=dict)
    catches_function_errors: frozenset[int] = frozenset()   # statement nids (Assign, CallStatement)
    skips_on_bad_index: frozenset[int] = frozenset()        # statement nids (array_oob=skip_statement)
    range_fors: Mapping[int, RangeFor] = field(default_factory=dict)       # For nid → how it is written
    inlined_fbs: Mapping[int, n.POU] = field(default_factory=dict)         # Call nid → the FB inlined
    direct_native: frozenset[int] = frozenset()             # Call nids of native FBs called directly
    array_refs: Mapping[int, ArrayRefReuse] = field(default_factory=dict)  # argument value nid → kept ArrayRef
    held_derefs: Mapping[int, HeldDeref] = field(default_factory=dict)     # loop nid → the dereference held


EMPTY_PLAN = ProjectPlan()
"""The plan of code lowered without a project body (the debugger's expressions)."""


def plan_project(analysis, settings, options: LowerOptions) -> ProjectPlan:
    """Every fact the generators need about the checked project `analysis`."""
    return _Planner(analysis, settings, options).plan()


@dataclass
class _Planner:
    a: object
    settings: object
    options: LowerOptions
    pous: dict[str, PouPlan] = field(default_factory=dict)
    function_errors: set[int] = field(default_factory=set)
    indexed: set[int] = field(default_factory=set)
    range_fors: dict[int, RangeFor] = field(default_factory=dict)
    inlined: dict[int, n.POU] = field(default_factory=dict)
    direct: set[int] = field(default_factory=set)
    array_refs: dict[int, ArrayRefReuse] = field(default_factory=dict)
    held: dict[int, HeldDeref] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.model = self.a.model   # type: ignore[attr-defined]
        self.facts = self.a.facts   # type: ignore[attr-defined]

    def plan(self) -> ProjectPlan:
        for key in sorted(self.model.pous):
            pou = self.model.pous[key]
            if pou.kind == "INTERFACE" or pou.native:
                continue
            node = self.a.pou_nodes.get(key)   # type: ignore[attr-defined]
            if node is not None:
                self.plan_body(pou, node, method=False)
            for method in pou.methods.values():
                if not method.abstract:
                    self.plan_body(method, self.a.method_nodes[method.key], method=True)  # type: ignore[attr-defined]
            for prop in pou.properties.values():
                for accessor in (prop.getter, prop.setter):
                    if accessor is not None and not accessor.abstract:
                        self.plan_body(accessor, self.a.method_nodes[accessor.key], method=True)  # type: ignore[attr-defined]
        return ProjectPlan(MappingProxyType(self.pous), frozenset(self.function_errors),
                           frozenset(self.indexed), MappingProxyType(self.range_fors),
                           MappingProxyType(self.inlined), frozenset(self.direct),
                           MappingProxyType(self.array_refs), MappingProxyType(self.held))

    # ---- one body
    def plan_body(self, pou: POUInfo, node, method: bool) -> None:
        body = node.body
        uses, calls, fors, call_statements, assigned = self.scan_body(body)
        by_reference = self.by_reference(pou, calls)
        frameless = False
        cached: dict[str, Variable] | None = None
        if method and self.options.frameless_methods:
            every = self.cached_vars(pou, node, uses, by_reference, fors, min_uses=0, outputs_local=True)
            if all(v.key in every for v in pou.variables.values() if v.section != "VAR_INST"):
                cached, frameless = every, True
        if cached is None:
            cached = self.cached_vars(pou, node, uses, by_reference, fors)
        self.pous[pou.key] = PouPlan(pou.key, MappingProxyType(uses), frozenset(assigned),
                                     frozenset(by_reference), MappingProxyType(cached), frameless)
        for s in fors:
            decision = self.range_for(s, cached)
            if decision is not None:
                self.range_fors[s.nid] = decision
        for s in call_statements:
            info = self.facts.calls.get(s.call.nid)
            if info is not None and info.is_fb and info.oo != "super_body":
                self.fb_call(s.call, info)
        if self.options.hold_derefs_in_loops and self.options.cache_locals:
            self.held_derefs(body, cached)

    def by_reference(self, pou: POUInfo, calls: list[n.Call]) -> set[str]:
        """Variables of the POU that code other than the body's own may read or write during a
        call: scalar in-out arguments and FUNCTION outputs (written through references), a
        FUNCTION's or METHOD's outputs, an FB's variables its methods reach, REF/ADR targets."""
        referenced: set[str] = set()
        for call in calls:
            info = self.facts.calls.get(call.nid)
            if info is None:
                continue
            for var, value in info.inputs:
                if var.section == IN_OUT and isinstance(value, n.Name):
                    referenced.add(value.parts[0].lower())
            if not info.is_fb:
                # a function writes its outputs through references at its end
                for var, target, _ in info.outputs:
                    if isinstance(target, n.Name):
                        referenced.add(target.parts[0].lower())
        if pou.kind != "METHOD" and self.has_members(pou):
            # its methods and properties read and write the instance's variables while the body
            # runs (own calls, calls back through interfaces): only temporaries and aggregates
            # may stay in Python locals
            referenced |= {v.key for v in pou.variables.values() if v.section != TEMP
                           and not isinstance(v.type, (t.StructType, t.ArrayType, t.FBType))}
        # a variable whose reference is taken (REF/ADR/REF=) may be read or written through it
        referenced |= {var for owner, var in self.facts.addressed if owner == pou.key}
        return referenced

    def has_members(self, pou: POUInfo) -> bool:
        cur: POUInfo | None = pou
        while cur is not None:
            if cur.methods or cur.properties:
                return True
            cur = self.model.pous.get(cur.base) if cur.base else None
        return False

    # ---- cache_locals, hot_path_cache, frameless_methods
    def cached_vars(self, pou: POUInfo, node, uses: Mapping[str, int], by_reference: set[str],
                    fors: list[n.For], min_uses: int = -1, outputs_local: bool = False) -> dict[str, Variable]:
        """`cache_locals`: variables a call may keep in Python locals (LOAD_FAST instead of
        attribute access).

        Safe for every variable of the POU's own instance/frame that is never passed by reference
        (as a scalar in-out argument): nothing else can observe it during the call. Aggregates
        (arrays, structs, FB instances) are never rebound, so a local alias is always safe; scalars
        are written back in a `finally`, so values survive RETURN and faults. `min_uses=0,
        outputs_local=True`: the candidates of a frameless METHOD (its outputs written back to the
        caller's references at its end).
        """
        if not self.options.cache_locals:
            return {}
        referenced = set(by_reference)
        if pou.kind in ("FUNCTION", "METHOD") and not outputs_local:
            referenced |= {v.key for v in pou.variables.values() if v.section == OUTPUT}
        hot = self.hot_path_uses(node, fors) if self.options.hot_path_cache and min_uses < 0 else None
        out = {}
        for var in pou.variables.values():
            if var.section in (EXTERNAL, GLOBAL, "VAR_INST") or var.key in referenced:
                continue
            if var.section == IN_OUT and not isinstance(var.type, (t.StructType, t.ArrayType, t.FBType)):
                continue  # a scalar in-out is a reference object; keep it on the instance
            if hot is not None and var.section != TEMP:
                if not hot_enough(var, hot):
                    continue
            # a local costs a load on entry (and a store on exit): worth it from a few uses on
            elif uses.get(var.key, 0) < (_CACHE_MIN_USES if min_uses < 0 else min_uses):
                continue
            out[var.key] = var
        return out

    def hot_path_uses(self, node, fors: list[n.For]) -> tuple[dict[str, float], set[str]]:
        """`hot_path_cache`: `hot_uses` of a body (loops already weigh their uses) and the names of
        its FOR variables (a range-FOR needs its variable in a Python local, so the hot-path rule
        always caches them)."""
        return hot_uses(node.body), {s.variable.parts[0].lower() for s in fors
                                     if isinstance(s.variable, n.Name) and len(s.variable.parts) == 1}

    # ---- one walk over a body: uses, calls, loops, assignments, statements that catch errors
    def scan_body(self, body) -> tuple[dict[str, int], list[n.Call], list[n.For], list[n.CallStatement], set[str]]:
        """One walk over a body. Returns how often each single-part name is used (loops weighted,
        as `name_uses`), its calls (as `calls_in`), FOR loops and call statements, and the root
        names it assigns (assignment and REF= targets, FOR variables, `=>` outputs and in-out
        arguments).

        On the way it marks every Assign and call statement containing a FUNCTION call (its
        instruction errors are caught at the statement) and, under `array_oob=skip_statement`,
        every statement containing an array access. A hit marks its enclosing statements
        innermost first and stops at one already marked (its own enclosing ones are too): linear
        in the body's size, where asking each statement for its subtree was quadratic in the
        nesting depth."""
        uses: dict[str, int] = {}
        calls: list[n.Call] = []
        fors: list[n.For] = []
        call_statements: list[n.CallStatement] = []
        assigned: set[str] = set()
        facts_calls = self.facts.calls
        skip = self.settings.array_oob is ArrayOob.SKIP_STATEMENT
        native: dict[int, type] = {}   # statements with a FUNCTION call inside → their class
        indexed = self.indexed
        open_statements: list = []
        weight = 1                     # LOOP_WEIGHT ** the loops open around the node
        leave, unknown, fields_of = _LEAVE, _UNKNOWN, CHILD_FIELDS
        name_cls, call_cls, index_cls, argument_cls = n.Name, n.Call, n.Index, n.Argument
        assign_classes, loops, statements = (n.Assign, n.RefAssign, n.AssignExpr), _LOOPS, _STATEMENTS
        get = uses.get
        stack: list = list(body)
        pop, push = stack.pop, stack.append
        while stack:
            node = pop()
            if node is leave:
                if open_statements.pop().__class__ in loops:
                    weight //= LOOP_WEIGHT
                continue
            cls = node.__class__
            names = fields_of.get(cls, unknown)
            if names is unknown:
                names = child_fields(cls)
            if names is None:
                if isinstance(node, tuple):
                    stack.extend(node)
                continue
            if cls is name_cls:
                if len(node.parts) == 1:
                    key = node.parts[0].lower()
                    uses[key] = get(key, 0) + weight
                continue   # a Name holds no nodes
            if cls is call_cls:
                calls.append(node)
                info = facts_calls.get(node.nid)
                if info is not None and not info.is_fb and not info.oo:
                    _mark(open_statements, native)
            elif cls is index_cls:
                if skip:
                    _mark(open_statements, indexed)
            elif cls is argument_cls:
                if node.kind != "input" and node.kind != "positional":
                    target = root_name(node.value)
                    if target is not None:
                        assigned.add(target)
            elif cls in statements:
                open_statements.append(node)
                push(leave)
                if cls in assign_classes:
                    target = root_name(node.target)
                    if target is not None:
                        assigned.add(target)
                elif cls is n.CallStatement:
                    call_statements.append(node)
                elif cls is n.For:
                    fors.append(node)
                    target = root_name(node.variable)
                    if target is not None:
                        assigned.add(target)
                if cls in loops:
                    weight *= LOOP_WEIGHT
            for name in names:
                push(getattr(node, name))
        guarded = (n.Assign, n.CallStatement)
        self.function_errors.update(nid for nid, cls in native.items() if cls in guarded)
        return uses, calls, fors, call_statements, assigned

    # ---- hold_derefs_in_loops
    def held_derefs(self, body, cached: Mapping[str, Variable]) -> None:
        """The outermost loops of a body for which `held_deref` holds."""
        if not any(isinstance(var.type, t.RefType) for var in cached.values()):
            return   # `held_deref` needs a Python-local reference to hold: no walk over the body
        inner: set[int] = set()
        found: dict[int, HeldDeref] = {}
        for node in walk(body):
            if node.__class__ in _LOOPS and node.nid not in inner:
                decision = self.held_deref(node, cached)
                if decision is not None:
                    found[node.nid] = decision
                    inner.update(x.nid for x in walk((node,)) if x is not node and x.__class__ in _LOOPS)
        self.held.update((nid, d) for nid, d in found.items() if nid not in inner)

    def held_deref(self, loop, cached: Mapping[str, Variable]) -> HeldDeref | None:
        """`hold_derefs_in_loops`: can `r^` be kept in a Python local for the whole loop?

        Only when nothing else in the loop can read or write its target: every variable the loop
        names is a Python local of this call (a variable whose reference is taken is never one), the
        only dereferences of scalars are of one reference `r`, which the loop never assigns, and
        there are no calls (a callee could reach anything) and no whole-aggregate assignments.
        Elements of fixed one-dimensional arrays (`arr[i]`) and scalar fields of structs and FB
        instances (`p.x`, `p.q.x`, `rp^.x`; `p` need not be a local: an aggregate is never rebound)
        may be read and written: `HeldDeref.bases` and `.arrays` are the objects whose fields and
        elements the loop touches, and the held copy of the loop runs only when `r` refers to none
        of them (checked before the loop; no fields in a project with UNIONs, whose members
        overlay the bytes of others). Faults inside the loop still see the value
        written so far: it is written back in a `finally`."""
        facts = self.facts
        ref: Variable | None = None
        written = False
        bases: list[n.Expr] = []       # the objects whose fields the loop reads or writes
        in_bases: set[int] = set()     # nodes of those base expressions (already checked)
        base_refs: set[str] = set()    # references dereferenced to reach a base (`rp` in `rp^.x`)
        lists: list[n.Name] = []        # the arrays whose elements the loop reads or writes
        for node in walk((loop,)):
            cls = node.__class__
            if node.nid in in_bases:
                continue
            if cls is n.Name:
                name = facts.names.get(node.nid)
                if name is None or node.nid in facts.auto_deref or (facts.props and node.nid in facts.props):
                    return None
                if name.kind in ("enum", "null", "result"):
                    continue
                if name.kind != "var" or name.variable is None or name.variable.key not in cached:
                    return None
                if t.is_aggregate(name.variable.type):
                    return None   # a whole-struct or array assignment writes the fields and elements
            elif cls is n.Deref:
                var = self.cached_ref(node.base, cached)
                if var is None or t.is_aggregate(var.type.target):   # type: ignore[union-attr]
                    return None
                if ref is not None and ref.key != var.key:
                    return None   # two references may name the same variable
                ref = var
            elif cls is n.Member:
                base = self.field_base(node, cached, in_bases, base_refs)
                if base is None:
                    return None
                bases.append(base)
            elif cls is n.Index:
                array = self.element_base(node)
                if array is None:
                    return None
                in_bases.add(array.nid)
                lists.append(array)
            elif cls in (n.Assign, n.RefAssign):
                if cls is n.RefAssign:
                    return None
                if isinstance(node.target, n.Deref) or (isinstance(node.target, n.BitAccess)
                                                        and _through_deref(node.target)):
                    written = True
            elif cls not in _HELD_OK:
                return None
        if ref is None or ref.key in base_refs:
            return None
        fixed = base_refs | {ref.key}
        for node in walk((loop,)):
            if isinstance(node, n.Assign) and isinstance(node.target, n.Name) and root_name(node.target) in fixed:
                return None
            if isinstance(node, n.For) and root_name(node.variable) in fixed:
                return None
        unique: dict[object, n.Expr] = {}
        for base in bases:
            unique.setdefault(_path_key(base), base)
        arrays: dict[object, n.Name] = {}
        for array in lists:
            arrays.setdefault(_path_key(array), array)
        return HeldDeref(ref, written, tuple(unique.values()), tuple(arrays.values()))

    def element_base(self, index: n.Index) -> n.Name | None:
        """For an element access in a held loop: the array variable, when it is a fixed
        one-dimensional array of scalars named by a variable (its list is never replaced)."""
        base = index.base
        ty = self.facts.types.get(base.nid)
        if not isinstance(base, n.Name) or not isinstance(ty, t.ArrayType) or ty.dims is None or len(ty.dims) != 1:
            return None
        if t.is_aggregate(ty.element) or len(index.indices) != 1 or base.nid in self.facts.auto_deref:
            return None
        name = self.facts.names.get(base.nid)
        if name is None or name.kind not in ("var", "global", "field") or name.variable is None:
            return None
        return base

    def cached_ref(self, e: n.Expr, cached: Mapping[str, Variable]) -> Variable | None:
        """The variable of `e` when it is a Python-local reference (not NULL's type), else None."""
        name = self.facts.names.get(e.nid) if isinstance(e, n.Name) else None
        if name is None or name.kind != "var" or name.variable is None or name.variable.key not in cached:
            return None
        ty = name.variable.type
        if not isinstance(ty, t.RefType) or ty.is_null or e.nid in self.facts.auto_deref:
            return None
        return name.variable

    def field_base(self, member: n.Member, cached: Mapping[str, Variable], in_bases: set[int],
                   base_refs: set[str]) -> n.Expr | None:
        """For a scalar field access in a held loop: its base (`p`, `p.q` or `rp^`) when it is an
        object the loop cannot rebind and that can be named before the loop without a fault."""
        if self.has_unions() or t.is_aggregate(self.facts.types.get(member.nid)):
            return None
        if self.facts.props and member.nid in self.facts.props:
            return None
        base = member.base
        chain = base
        while True:
            if self.facts.props and chain.nid in self.facts.props:
                return None
            if not isinstance(self.facts.types.get(chain.nid), (t.StructType, t.FBType)):
                return None
            if not isinstance(chain, n.Member):
                break
            chain = chain.base
        if isinstance(chain, n.Name):
            # a struct or FB variable, a Python local or not, is never rebound during a call
            name = self.facts.names.get(chain.nid)
            if name is None or name.kind not in ("var", "global", "field") or name.variable is None:
                return None
            if chain.nid in self.facts.auto_deref:
                return None
        elif isinstance(chain, n.Deref) and chain is base:
            var = self.cached_ref(chain.base, cached)
            if var is None:
                return None
            base_refs.add(var.key)
            in_bases.add(chain.base.nid)
        else:
            return None   # `rp^.q.x`: `rp^.q` cannot be named before the loop when rp is NULL
        node = base
        while True:
            in_bases.add(node.nid)
            if not isinstance(node, n.Member):
                break
            node = node.base
        return base

    def has_unions(self) -> bool:
        if not hasattr(self, "_unions"):
            self._unions = any(isinstance(st, t.UnionType) for st in self.model.structs.values())
        return self._unions

    # ---- range_for, hoist_bounds
    def range_for(self, s: n.For, cached: Mapping[str, Variable]) -> RangeFor | None:
        var_type = self.facts.types[s.variable.nid]
        step = self.facts.consts.get(s.step.nid) if s.step is not None else 1
        if not self.range_for_ok(s, step, cached):
            return None
        assert isinstance(var_type, t.IntType) and isinstance(step, int)
        key = s.variable.parts[0].lower()
        start = self.facts.consts.get(s.start.nid)
        hoisted = tuple(sorted(self.hoistable_accesses(s.body, key))) if self.options.hoist_bounds else ()
        first, last = self.const_in(s.start, var_type), self.const_in(s.end, var_type)
        bounds = (first, last) if first is not None and last is not None else None
        fits = None
        if bounds is not None and hoisted:
            low, high = bounds if step > 0 else bounds[::-1]
            fits = all(low + c >= lo and high + c <= hi for c, lo, hi in hoisted)
        return RangeFor(key, step, start if isinstance(start, int) else None, var_type, hoisted, bounds, fits)

    def const_in(self, expr: n.Expr, var_type: t.IntType) -> int | None:
        """The constant value of `expr` when it has one inside `var_type`'s range, else None."""
        value = self.facts.consts.get(expr.nid)
        if isinstance(value, int) and not isinstance(value, bool) and var_type.lo <= value <= var_type.hi:
            return value
        return None

    def range_for_ok(self, s: n.For, step: object, cached: Mapping[str, Variable]) -> bool:
        """`range_for`: can this FOR become a Python `for … in range()` (same semantics, much
        faster)?

        Needs: a constant non-zero step, the end evaluated once, a loop variable held in a local
        that the body never assigns, and no EXIT/RETURN (so a wrap-around at the type's limit
        is a genuinely endless loop, reported as a fault instead of hanging)."""
        if not self.options.range_for:
            return False
        if not isinstance(step, int) or isinstance(step, bool) or step == 0:
            return False
        if self.settings.for_end_eval is not ForEndEval.ONCE:
            return False
        ref = self.facts.names.get(s.variable.nid)
        if ref is None or ref.kind != "var" or ref.variable is None or ref.variable.key not in cached:
            return False
        key = ref.variable.key
        for node in walk(s.body):
            if isinstance(node, (n.Exit, n.Return)):
                return False
            if isinstance(node, n.Assign) and root_name(node.target) == key:
                return False
            if isinstance(node, n.For) and root_name(node.variable) == key:
                return False
            if isinstance(node, n.Argument) and node.kind != "input" and node.kind != "positional" \
                    and root_name(node.value) == key:
                return False
        return True

    def hoistable_accesses(self, body, key: str) -> set[tuple[int, int, int]]:
        """`hoist_bounds`: (offset, lo, hi) of every 1-D array access indexed by the loop variable
        (+/- const)."""
        found: set[tuple[int, int, int]] = set()
        for node in walk(body):
            if isinstance(node, n.Index) and len(node.indices) == 1:
                base_type = self.facts.types.get(node.base.nid)
                if isinstance(base_type, t.ArrayType) and base_type.dims and len(base_type.dims) == 1:
                    c = loop_offset(self.facts, node.indices[0], key)
                    if c is not None:
                        lo, hi = base_type.dims[0]
                        found.add((c, lo, hi))
        return found

    # ---- FB calls: inline_small_fbs, direct_native_calls, reuse_array_refs
    def fb_call(self, call: n.Call, info: CallInfo) -> None:
        inlined = self.inlinable_fb(info)
        if inlined is not None:
            self.inlined[call.nid] = inlined
        elif self.direct_native_call(info):
            self.direct.add(call.nid)
        for var, value in info.inputs:
            if var.section != IN_OUT and isinstance(var.type, t.StructType):
                continue
            if var.section != IN_OUT and isinstance(var.type, t.ArrayType) and var.type.dims is not None:
                continue
            reuse = self.reused_array_ref(var, value)
            if reuse is not None:
                self.array_refs[value.nid] = reuse

    def inlinable_fb(self, info: CallInfo) -> n.POU | None:
        """`inline_small_fbs`: the body of a tiny FB (R_TRIG, F_TRIG, SR, RS: at most
        `_INLINE_FB_STATEMENTS` assignments of its own variables from expressions of its own
        variables and literals) is lowered into the caller, with the instance as the owner of its
        variables: the same stores in the same order, one Python call less. None when not applied.
        Not for native FBs, FBs with methods, properties, a base, temporaries, in-outs or
        externals, nor when a POU extends the FB (a reference could reach a derived instance)."""
        pou = info.pou
        if not self.options.inline_small_fbs or pou.native or info.oo or pou.kind != "FUNCTION_BLOCK":
            return None
        if pou.methods or pou.properties or pou.base is not None or pou.interfaces:
            return None
        if any(v.section not in (INPUT, OUTPUT, LOCAL) for v in pou.variables.values()):
            return None
        node = self.a.pou_nodes.get(pou.key)   # type: ignore[attr-defined]
        if node is None or not 0 < len(node.body) <= _INLINE_FB_STATEMENTS:
            return None
        if any(other.base == pou.key for other in self.model.pous.values()):
            return None
        for stmt in node.body:
            if not isinstance(stmt, n.Assign) or not self.own_simple(stmt.target, pou, target=True) \
                    or not self.own_simple(stmt.value, pou):
                return None
        return node

    def own_simple(self, e: n.Expr, pou, target: bool = False) -> bool:
        """A plain variable of `pou` (its own instance's), or for a value also a literal or
        NOT/AND/OR/XOR of such: code that cannot call, index, fault or reach another object."""
        if isinstance(e, n.Name):
            ref = self.facts.names.get(e.nid)
            return ref is not None and ref.kind == "var" and ref.variable is not None \
                and ref.variable.key in pou.variables and e.nid not in self.facts.auto_deref \
                and isinstance(ref.variable.type, t.BoolType)
        if target:
            return False
        if isinstance(e, n.BoolLiteral):
            return True
        if isinstance(e, n.Unary):
            return e.op == "NOT" and self.own_simple(e.operand, pou)
        if isinstance(e, n.Binary):
            return e.op in ("AND", "AMP", "OR", "XOR") and self.own_simple(e.left, pou) \
                and self.own_simple(e.right, pou)
        return False

    def direct_native_call(self, info: CallInfo) -> bool:
        """`direct_native_calls`: a native FB (TON, SktTCPSend, ...) called straight through its
        implementation, `inst._impl.call(inst, _ctx)`, instead of through the class's `__call__`
        that does only that (one Python frame less per call). The instance is of exactly that
        class: the checker lets no POU extend a native FB."""
        return self.options.direct_native_calls and info.pou.native and not info.oo

    def reused_array_ref(self, var: Variable, value: n.Expr) -> ArrayRefReuse | None:
        """`reuse_array_refs`: an ARRAY[*] argument of an FB call that is a fixed array of the
        caller (`SendDat := Data[0]`, `Buf := Data`) keeps the `ArrayRef` the instance already
        holds when it names the same list from the same element on, instead of building a new
        one every call (the thesis passes two a scan per CBT FB). An `ArrayRef` is never changed
        after it is made, and a fixed array's list is never replaced (assignments copy into it),
        so the kept one is equal in every respect. A constant element index is checked here, at
        compile time. None when not applied (the plain `arg_code` path)."""
        if not self.options.reuse_array_refs or not isinstance(var.type, t.ArrayType) or var.type.dims is not None \
                or var.type.rank > 1:   # an ARRAY[*, *] gets an `_OpenArray`, not an `ArrayRef`
            return None
        vtype = self.facts.types.get(value.nid)
        lo = 0
        if value.nid in self.facts.array_from_element:
            assert isinstance(value, n.Index)
            base_type = self.facts.types[value.base.nid]
            if not isinstance(base_type, t.ArrayType) or base_type.dims is None or len(value.indices) != 1:
                return None
            first, last = base_type.dims[0]
            const = self.facts.consts.get(value.indices[0].nid)
            if not isinstance(const, int) or isinstance(const, bool) or not first <= const <= last:
                return None
            return ArrayRefReuse(value.base, const - first, lo)
        if isinstance(vtype, t.ArrayType) and vtype.dims is not None:
            if self.settings.open_array_bounds is OpenArrayBounds.ACTUAL:
                lo = vtype.dims[0][0]
            return ArrayRefReuse(value, 0, lo)
        return None


def _path_key(e: n.Expr) -> object:
    """The same access path written twice gives the same key (`p` and `p` in `p.x`, `p.y`)."""
    if isinstance(e, n.Name):
        return ("name", tuple(part.lower() for part in e.parts))
    if isinstance(e, n.Member):
        return ("member", _path_key(e.base), e.name.lower())
    assert isinstance(e, n.Deref)
    return ("deref", _path_key(e.base))


def _through_deref(target: n.Expr) -> bool:
    """A bit or part of a dereference (`r^.3 := TRUE` stores through `r`)."""
    while isinstance(target, n.BitAccess):
        target = target.base
    return isinstance(target, n.Deref)


def hot_enough(var: Variable, hot: tuple[dict[str, float], set[str]]) -> bool:
    """`hot_path_cache`: is a local worth its load on entry (and store on exit) on a typical
    call? Yes when the uses one call is expected to make (branches weighted, loops multiplied
    by `hot_uses`) reach the threshold; an aggregate is only aliased (no write-back), so it pays
    off sooner. A FOR variable (a range-FOR needs it in a local) pays off sooner too; one whose
    loops sit in a cold branch (the thesis FBs' checksum loop in one step of twelve, run once per
    command, while the prologue and write-back would run on every call) stays on the instance
    and its loop is the plain WHILE form. A temporary keeps the plain rule: uncached, it is reset
    on the instance every call anyway."""
    counts, for_vars = hot
    if var.key in for_vars:
        return counts.get(var.key, 0.0) >= _HOT_MIN_USES_FOR
    aggregate = isinstance(var.type, (t.StructType, t.ArrayType, t.FBType))
    return counts.get(var.key, 0.0) >= (_HOT_MIN_USES_AGGREGATE if aggregate else _HOT_MIN_USES)


def loop_offset(facts, ix: n.Expr, key: str) -> int | None:
    """c when `ix` is `key`, `key + c` or `key - c` (constant c), else None."""
    if isinstance(ix, n.Name) and len(ix.parts) == 1 and ix.parts[0].lower() == key:
        return 0
    if isinstance(ix, n.Binary) and ix.op in ("PLUS", "MINUS") and isinstance(ix.left, n.Name) \
            and len(ix.left.parts) == 1 and ix.left.parts[0].lower() == key:
        c = facts.consts.get(ix.right.nid)
        if isinstance(c, int) and not isinstance(c, bool) and ix.right.nid in facts.untyped:
            return c if ix.op == "PLUS" else -c
    return None


def _mark(open_statements: list, marked) -> None:
    """Mark the open statements (a set of nids, or a dict nid → class), innermost first."""
    add = marked.add if isinstance(marked, set) else None
    for s in reversed(open_statements):
        nid = s.nid
        if nid in marked:
            return
        if add is not None:
            add(nid)
        else:
            marked[nid] = s.__class__


_LEAVE = object()            # on the walk's stack: the statement opened last is left
_UNKNOWN = object()


_LOOPS = frozenset({n.For, n.While, n.Repeat})
_STATEMENTS = frozenset(cls for cls in vars(n).values() if isinstance(cls, type) and issubclass(cls, n.Statement))
# what a loop with a held dereference may contain besides names, dereferences and assignments
_HELD_OK = frozenset({n.IntLiteral, n.RealLiteral, n.BoolLiteral, n.StringLiteral, n.TimeLiteral,
                      n.HashLiteral, n.Unary, n.Binary, n.BitAccess, n.PartialAccess, n.If, n.Case,
                      n.CaseLabel, n.For, n.While, n.Repeat, n.Exit, n.Continue, n.Return, n.Empty})
_CACHE_MIN_USES = 3          # uses of a variable in a body (a use inside a loop counts as many)
# `hot_path_cache`: expected uses per call (see stvm/lower/hot_uses.py) from which a local pays:
# a cached scalar costs ~6 bytecodes (load on entry, store back on exit) and saves ~1.5 per use
_HOT_MIN_USES = 3.0
_HOT_MIN_USES_AGGREGATE = 2.0
_HOT_MIN_USES_FOR = 2.0
_INLINE_FB_STATEMENTS = 4
