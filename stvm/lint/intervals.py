"""Integer ranges and string lengths per program point: interval analysis with constant
propagation, on the CFG and across scans.

Abstract state: place key ('x', 'cbt.connected', 'buf[0]') → interval `(lo, hi)`. For integer,
BOOL (0/1) and enumeration places the interval is the value; for STRING places it is the length
in bytes. A key that is absent has its declared range (the whole type, or the subrange of its
declaration); so an assignment the analysis cannot follow just drops keys, which is always
sound.

What a call of the POU starts from (`next_call`):

* VAR and VAR_OUTPUT of a FUNCTION_BLOCK keep the values the previous call left (and start at
  their initial values), so a state variable's range is the set of values the body assigns;
* VAR_TEMP, and every variable of a FUNCTION, start at their initial value on each call;
* inputs, in-outs and globals can be anything of their type (the caller, other programs and
  the HMI write them);
* Choice: variables of a PROGRAM that the program assigns are internal and persistent like an
  FB's (on an NJ only global variables are published to HMIs and OPC UA); one it never assigns
  is an input set from outside (stvm's `--set`, a scenario, the debugger) and can be anything.

Conditions refine the state on each branch (`x < 10`, `NOT flag`, `LEN(s) > 0`, CASE labels),
so a branch whose refined state is empty is unreachable: that is the per-path reachability the
rules use. PLCopen outputs `Done`, `Busy`, `Error`, `CommandAborted` of one instance exclude each
other, so `IF fb.Done THEN … END_IF; IF fb.Error THEN …` cannot take both branches in one scan.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right

from stvm.lint.cfg import CFG, Edge, Node
from stvm.lint.dataflow import Solution, solve
from stvm.lint.facts_view import (EXTERNAL, GLOBAL, IN_OUT, LOCAL, NOT_CONST, OUTPUT, TEMP, FactsView,
                             node_calls, node_subexprs, place_key,
                             root_expr)
from stvm.semantics import types as t
from stvm.settings import ByteToStringFormat, EnumDefault
from stvm.syntax import nodes as n
from stvm.lint.access import node_accesses

Interval = tuple[int, int]
State = dict[str, Interval]

# PLCopen status outputs: at most one is TRUE at a time
_EXCLUSIVE_OUTPUTS = ("done", "busy", "error", "commandaborted")

# longest decimal text of each integer type (sign included), for *_TO_STRING lengths
_DECIMAL_WIDTH = {"SINT": 4, "INT": 6, "DINT": 11, "LINT": 20, "USINT": 3, "UINT": 5, "UDINT": 10, "ULINT": 20}
_HEX_WIDTH = {"BYTE": 2, "WORD": 4, "DWORD": 8, "LWORD": 16}
_REAL_WIDTH = {"REAL": 15, "LREAL": 25}   # REAL_TO_STRING: shortest round-trip text with exponent
MAX_STRING_BYTES = t.STRING.max_bytes      # 1985: Sysmac's string function result limit
_INT_ROUNDS = 2       # threshold widenings of an integer before it widens to its declared limits
_LOOP_INT_ROUNDS = 4  # the same at a loop head (inside one call: cheap, and loop bounds are constants)
_STRING_ROUNDS = 4    # plain joins of a string length before it widens to the declared size


def type_range(ty: t.Type | None) -> Interval | None:
    """The interval a value (or, for strings, the length) of this type can take; None if untracked."""
    if isinstance(ty, t.BoolType):
        return (0, 1)
    if isinstance(ty, t.IntType):
        return (ty.lo, ty.hi)
    if isinstance(ty, t.EnumType):
        values = [v for _, v in ty.members]
        return (min(values), max(values)) if values else None
    if isinstance(ty, t.StringType):
        return (0, ty.max_bytes)
    return None


def hull(a: Interval, b: Interval) -> Interval:
    return (min(a[0], b[0]), max(a[1], b[1]))


def meet(a: Interval, b: Interval) -> Interval | None:
    lo, hi = max(a[0], b[0]), min(a[1], b[1])
    return (lo, hi) if lo <= hi else None


def is_point(iv: Interval | None) -> bool:
    return iv is not None and iv[0] == iv[1]


def fmt(iv: Interval) -> str:
    return str(iv[0]) if iv[0] == iv[1] else f"{iv[0]}..{iv[1]}"


class Evaluator:
    """Abstract evaluation of expressions in a state (no side effects)."""

    def __init__(self, facts: FactsView, settings, declared: dict[str, Interval]) -> None:
        self.facts = facts
        self.settings = settings
        self.declared = declared        # root variable key → declared subrange (narrower than its type)

    # ---- places
    def default(self, key: str, ty: t.Type | None) -> Interval | None:
        rng = type_range(ty)
        if rng is not None and key in self.declared and not isinstance(ty, t.StringType):
            return meet(rng, self.declared[key]) or rng
        return rng

    def read(self, expr: n.Expr, state: State) -> Interval | None:
        ty = self.facts.type_of(expr)
        key = place_key(expr, self.facts)
        if key is not None and key in state:
            return state[key]
        return self.default(key or "", ty)

    # ---- values
    def eval(self, expr: n.Expr, state: State) -> Interval | None:
        """The interval of an integer/BOOL/enum expression, the length interval of a string
        expression, or None (untracked: REAL, TIME, structs …)."""
        value = self.facts.const(expr)
        ty = self.facts.type_of(expr)
        if value is not NOT_CONST:
            if isinstance(value, bool):
                return (int(value), int(value))
            if isinstance(value, int) and not isinstance(ty, (t.TimeType, t.RealType)):
                return (value, value)
            if isinstance(value, bytes):
                return (len(value), len(value))
        if isinstance(expr, (n.Name, n.Member, n.Index)):
            return self.read(expr, state)
        if isinstance(expr, n.Unary):
            inner = self.eval(expr.operand, state)
            if inner is None:
                return None
            if expr.op == "NOT":
                return (1 - inner[1], 1 - inner[0]) if isinstance(ty, t.BoolType) else type_range(ty)
            if expr.op == "MINUS" and isinstance(ty, t.IntType):
                return self.fit((-inner[1], -inner[0]), ty)
            return inner if expr.op == "PLUS" else type_range(ty)
        if isinstance(expr, n.Binary):
            return self.binary(expr, state, ty)
        if isinstance(expr, n.Call):
            return self.call(expr, state, ty)
        return type_range(ty)

    def fit(self, iv: Interval, ty: t.Type | None) -> Interval | None:
        """An exact mathematical interval, as the type holds it (wrapping → the whole type)."""
        rng = type_range(ty)
        if rng is None:
            return None
        if isinstance(ty, t.StringType):
            return (min(iv[0], rng[1]), min(iv[1], rng[1]))
        return iv if rng[0] <= iv[0] and iv[1] <= rng[1] else rng

    def math(self, expr: n.Binary, state: State) -> Interval | None:
        """The exact (unwrapped) result interval of + - * / MOD, or None."""
        a = self.eval(expr.left, state)
        b = self.eval(expr.right, state)
        if a is None or b is None:
            return None
        op = expr.op
        if op == "PLUS":
            return (a[0] + b[0], a[1] + b[1])
        if op == "MINUS":
            return (a[0] - b[1], a[1] - b[0])
        if op == "STAR":
            corners = [a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]]
            return (min(corners), max(corners))
        if op == "SLASH":
            if b[0] <= 0 <= b[1]:
                if b == (0, 0):
                    return None
                # split around 0: the divisor's nearest non-zero values
                parts = [p for p in ((b[0], -1), (1, b[1])) if p[0] <= p[1]]
            else:
                parts = [b]
            values = []
            for lo, hi in parts:
                for x in (a[0], a[1]):
                    for y in (lo, hi):
                        values.append(int(x / y))   # ST integer division truncates toward zero
            return (min(values), max(values))
        if op == "MOD":
            if b[0] > 0 and a[0] >= 0:
                return (0, min(a[1], b[1] - 1))
            return None
        return None

    def binary(self, expr: n.Binary, state: State, ty: t.Type | None) -> Interval | None:
        op = expr.op
        if op in ("EQ", "NE", "LT", "GT", "LE", "GE"):
            return self.compare(expr, state)
        if op in ("AND", "AMP", "OR", "XOR"):
            a = self.eval(expr.left, state)
            b = self.eval(expr.right, state)
            if isinstance(ty, t.BoolType) and a is not None and b is not None:
                if op in ("AND", "AMP"):
                    return (a[0] & b[0], a[1] & b[1])
                if op == "OR":
                    return (a[0] | b[0], a[1] | b[1])
                if is_point(a) and is_point(b):
                    return (a[0] ^ b[0],) * 2
                return (0, 1)
            if op in ("AND", "AMP") and a is not None and b is not None and isinstance(ty, t.IntType):
                # a mask keeps a non-negative value at most the mask
                for mask, other in ((b, a), (a, b)):
                    if is_point(mask) and mask[0] >= 0 and other[0] >= 0:
                        return (0, min(mask[0], other[1]))
            return type_range(ty)
        if isinstance(ty, t.IntType):
            exact = self.math(expr, state)
            return self.fit(exact, ty) if exact is not None else type_range(ty)
        return type_range(ty)

    def compare(self, expr: n.Binary, state: State) -> Interval:
        a = self.eval(expr.left, state)
        b = self.eval(expr.right, state)
        operand = self.facts.operand_type(expr)
        if a is None or b is None or isinstance(operand, (t.RealType, t.StringType)) \
                or isinstance(self.facts.type_of(expr.left), t.StringType):
            return (0, 1)
        op = expr.op
        always = {"LT": a[1] < b[0], "LE": a[1] <= b[0], "GT": a[0] > b[1], "GE": a[0] >= b[1],
                  "EQ": is_point(a) and a == b, "NE": a[1] < b[0] or b[1] < a[0]}[op]
        never = {"LT": a[0] >= b[1], "LE": a[0] > b[1], "GT": a[1] <= b[0], "GE": a[1] < b[0],
                 "EQ": a[1] < b[0] or b[1] < a[0], "NE": is_point(a) and a == b}[op]
        if always:
            return (1, 1)
        if never:
            return (0, 0)
        return (0, 1)

    # ---- calls
    def args(self, expr: n.Call) -> tuple[object, dict[str, n.Expr], list[n.Expr]]:
        info = self.facts.call(expr)
        if info is None:
            return None, {}, []
        named = {var.key: value for var, value in info.inputs}
        ordered = [value for _, value in info.inputs] + list(info.extra)
        return info, named, ordered

    def call(self, expr: n.Call, state: State, ty: t.Type | None) -> Interval | None:
        info, named, ordered = self.args(expr)
        if info is None or info.is_fb or getattr(info, "oo", ""):
            return type_range(ty)   # (a METHOD named like a standard function is not one)
        name = info.pou.name.upper()
        length = self.string_length
        if name == "LEN" and ordered:
            inner = length(ordered[0], state)
            return (inner[0], min(inner[1], 65535)) if inner is not None else type_range(ty)
        if name == "CONCAT":
            total = (0, 0)
            for arg in ordered:
                piece = length(arg, state) or (0, MAX_STRING_BYTES)
                total = (total[0] + piece[0], total[1] + piece[1])
            return self.fit(total, ty)
        if name == "FIND" and ordered:
            inner = length(ordered[0], state)
            return (0, inner[1]) if inner is not None else type_range(ty)
        if name in ("LEFT", "RIGHT", "MID") and len(ordered) >= 2:
            inner = length(ordered[0], state) or (0, MAX_STRING_BYTES)
            count = self.eval(ordered[1], state) or (0, MAX_STRING_BYTES)
            return (0, max(0, min(inner[1], count[1])))
        if name in ("DELETE",) and ordered:
            inner = length(ordered[0], state) or (0, MAX_STRING_BYTES)
            return (0, inner[1])
        if name in ("INSERT", "REPLACE") and len(ordered) >= 2:
            a = length(ordered[0], state) or (0, MAX_STRING_BYTES)
            b = length(ordered[1], state) or (0, MAX_STRING_BYTES)
            return self.fit((0, a[1] + b[1]), ty)
        if name == "ARYTOSTRING" and len(ordered) >= 2:
            count = self.eval(ordered[1], state) or (0, MAX_STRING_BYTES)
            return (0, max(0, min(count[1], MAX_STRING_BYTES, self.elements_from(ordered[0]))))
        if name == "REALTOFORMATSTRING":
            return self.format_length(named, state)
        if name.endswith("_TO_STRING"):
            source = name[: -len("_TO_STRING")]
            if source in _DECIMAL_WIDTH:
                value = self.eval(ordered[0], state) if ordered else None
                if value is not None:
                    return (_decimal_digits(value, shortest=True), _decimal_digits(value))
                return (1, _DECIMAL_WIDTH[source])
            if source in _HEX_WIDTH:
                width = _HEX_WIDTH[source]
                fixed = self.settings.byte_to_string_format is ByteToStringFormat.HEX_PAD2
                return (width if fixed else 1, width)
            if source == "BOOL":
                return (4, 5)
            if source in _REAL_WIDTH:
                return (1, _REAL_WIDTH[source])
            return type_range(ty)
        if name in ("MIN", "MAX") and ordered:
            values = [self.eval(a, state) for a in ordered]
            if any(v is None for v in values):
                return type_range(ty)
            pick = min if name == "MIN" else max
            return (pick(v[0] for v in values), pick(v[1] for v in values))  # type: ignore[index]
        if name == "LIMIT" and len(ordered) == 3:
            lo, value, hi = (self.eval(a, state) for a in ordered)
            if lo is None or value is None or hi is None:
                return type_range(ty)
            return (max(lo[0], min(value[0], hi[1])), min(hi[1], max(value[1], lo[0])))
        if name == "ABS" and ordered:
            value = self.eval(ordered[0], state)
            if value is None or not isinstance(ty, t.IntType):
                return type_range(ty)
            low = 0 if value[0] <= 0 <= value[1] else min(abs(value[0]), abs(value[1]))
            return self.fit((low, max(abs(value[0]), abs(value[1]))), ty)
        if name in ("SEL",) and len(ordered) == 3:
            a, b = self.eval(ordered[1], state), self.eval(ordered[2], state)
            return hull(a, b) if a is not None and b is not None else type_range(ty)
        if name == "MOVE" and ordered:
            value = self.eval(ordered[0], state)
            return self.fit(value, ty) if value is not None else type_range(ty)
        if "_TO_" in name and ordered and isinstance(ty, (t.IntType, t.BoolType)):
            value = self.eval(ordered[0], state)
            source = self.facts.type_of(ordered[0])
            if value is not None and isinstance(source, (t.IntType, t.BoolType, t.EnumType)):
                return self.fit(value, ty)
        return type_range(ty)

    def elements_from(self, expr: n.Expr) -> int:
        """How many array elements an array argument covers (`buf[k]`: from k to the end)."""
        if isinstance(expr, n.Index) and len(expr.indices) == 1:
            base = self.facts.type_of(expr.base)
            first = self.facts.const(expr.indices[0])
            if isinstance(base, t.ArrayType) and base.dims and len(base.dims) == 1 and isinstance(first, int):
                return max(0, base.dims[0][1] - first + 1)
        ty = self.facts.type_of(expr)
        if isinstance(ty, t.ArrayType) and ty.dims:
            return ty.length
        return MAX_STRING_BYTES

    def string_length(self, expr: n.Expr, state: State) -> Interval | None:
        ty = self.facts.type_of(expr)
        if not isinstance(ty, t.StringType):
            return None
        return self.eval(expr, state)

    def format_length(self, named: dict[str, n.Expr], state: State) -> Interval:
        """RealToFormatString's text length: sign, up to 39 integer digits (REAL max 3.4E38),
        the decimals, left-padded to MinLen (sysmac.md 6)."""
        decimals = self.eval(named["decplace"], state) if "decplace" in named else (6, 6)
        min_len = self.eval(named["minlen"], state) if "minlen" in named else (0, 0)
        exponent = self.eval(named["exponent"], state) if "exponent" in named else (0, 0)
        decimals = decimals or (0, 7)
        min_len = min_len or (0, 24)
        exponent = exponent or (0, 1)
        longest = 1 + (39 if exponent[0] == 0 else 1) + (1 + decimals[1] if decimals[1] > 0 else 0)
        if exponent[1] == 1:
            longest = max(longest, 1 + 1 + 1 + decimals[1] + 5)
        return (max(1, min_len[0]), max(longest, min_len[1]))


class RangeAnalysis:
    """The interval analysis of one POU (a `dataflow.ForwardAnalysis`)."""

    def __init__(self, cfg: CFG, pou_info, facts: FactsView, settings,
                 alias_ranges: dict[str, Interval] | None = None) -> None:
        self.cfg = cfg
        self.pou = pou_info
        self.facts = facts
        self.settings = settings
        self.sections = {key: var.section for key, var in pou_info.variables.items()}
        self.declared = declared_subranges(cfg.pou, alias_ranges or {})
        self.ev = Evaluator(facts, settings, self.declared)
        kind = pou_info.kind
        self.persistent = {key for key, var in pou_info.variables.items()
                           if kind in ("FUNCTION_BLOCK", "PROGRAM") and var.section in (LOCAL, OUTPUT)
                           and not var.constant}
        if kind == "PROGRAM":
            # a program variable the program never assigns is its input from outside
            self.persistent &= _assigned_roots(cfg, facts)
        fresh_sections = (LOCAL, OUTPUT, TEMP) if kind == "FUNCTION" else (TEMP,)
        self.fresh = {key for key, var in pou_info.variables.items() if var.section in fresh_sections}
        self.thresholds = _thresholds(cfg, facts)
        self.key_types: dict[str, t.Type] = {}
        self.parents: set[str] = set()   # keys that have (or had) sub-keys in some state
        self.limits: dict[str, Interval] = {}  # key → its declared range, for the final widening
        self._loop_writes: dict[int, set[str]] = {}
        self.string_keys: set[str] = {key for key, var in pou_info.variables.items()
                                      if isinstance(var.type, t.StringType)}
        self._initial_values = self._initial_values_of(self.persistent | self.fresh)
        self._fresh_values = {k: v for k, v in self._initial_values.items() if k in self.fresh}

    # ---- initial values
    def _initial_values_of(self, keys: set[str]) -> State:
        out: State = {}
        for key in keys:
            var = self.pou.variables[key]
            value = _initial(var, self.settings)
            if value is not None:
                out[key] = value
                limits = self.ev.default(key, var.type)
                if limits is not None:
                    self.limits[key] = limits
        return out

    def initial(self) -> State:
        return dict(self._initial_values)

    def next_call(self, exit_state: State) -> State:
        keep = {k: v for k, v in exit_state.items() if k.split(".", 1)[0].split("[", 1)[0] in self.persistent}
        keep.update(self._fresh_values)
        return keep

    # ---- lattice
    def join(self, a: State, b: State) -> State:
        if a is b:
            return a
        get = b.get
        return {key: va if va == vb else (va[0] if va[0] < vb[0] else vb[0], va[1] if va[1] > vb[1] else vb[1])
                for key, va in a.items() if (vb := get(key)) is not None}

    def leq(self, a: State, b: State) -> bool:
        if a is b:
            return True
        get = a.get
        for key, vb in b.items():
            va = get(key)
            if va is None or va[0] < vb[0] or va[1] > vb[1]:
                return False
        return True

    def widen(self, old: State, new: State, rounds: int = 1, at: Node | None = None) -> State:
        """Integers: to the next program constant for the first rounds, then to the declared
        limits. String lengths: plain joins (a chain of CONCATs across steps settles in a few
        scans), then the declared size (a string that grows every scan). At a loop head only
        what the loop writes is widened: the rest settles with the enclosing loop (or scan)."""
        out = {}
        th = self.thresholds
        written = self.loop_writes(at) if at is not None and at.loop_head else None
        for key, vn in new.items():
            vo = old.get(key)
            if vo is None:
                continue
            if written is not None and key.split(".", 1)[0].split("[", 1)[0] not in written:
                out[key] = vn
                continue
            lo, hi = vn
            limits = self.limits.get(key)
            is_string = key in self.string_keys
            final = rounds > (_STRING_ROUNDS if is_string else _INT_ROUNDS if written is None else _LOOP_INT_ROUNDS)
            if is_string and not final:
                out[key] = vn
                continue
            if final and limits is not None:
                if lo < vo[0]:
                    lo = limits[0]
                if hi > vo[1]:
                    hi = limits[1]
                out[key] = (lo, hi)
                continue
            if final:
                continue   # no known limits: drop the key (its declared range)
            if lo < vo[0]:
                i = bisect_right(th, lo) - 1
                lo = th[i] if i >= 0 else -(1 << 64)
            if hi > vo[1]:
                i = bisect_left(th, hi)
                hi = th[i] if i < len(th) else (1 << 64)
            out[key] = (lo, hi)
        return out

    def loop_writes(self, head: Node) -> set[str]:
        """Root variables that the loop of this head writes (its body, its own FOR step)."""
        cached = self._loop_writes.get(head.index)
        if cached is None:
            inner = {s.nid for s in _statements_in(head.stmt)}
            cached = {a.var.key for node in self.cfg.nodes if node.stmt is not None and node.stmt.nid in inner
                      for a in node_accesses(node, self.facts) if a.kind != "read"}
            self._loop_writes[head.index] = cached
        return cached

    # ---- transfer
    def transfer(self, node: Node, state: State) -> State:
        kind = node.kind
        calls = node_calls(node)
        if kind in ("entry", "exit", "join") or (kind in ("branch", "case", "for_test") and not calls):
            return state
        stmt = node.stmt
        state = dict(state)
        for call in calls:
            self.call_effects(call, state)
        if kind == "assign":
            self.write(stmt.target, self.ev.eval(stmt.value, state), state)  # type: ignore[union-attr]
        elif kind == "for_init":
            self.write(stmt.variable, self.ev.eval(stmt.start, state), state)  # type: ignore[union-attr]
        elif kind == "for_step":
            var = stmt.variable  # type: ignore[union-attr]
            step = self.ev.eval(stmt.step, state) if stmt.step is not None else (1, 1)  # type: ignore[union-attr]
            current = self.ev.eval(var, state)
            ty = self.facts.type_of(var)
            if current is None or step is None:
                self.write(var, None, state)
            else:
                self.write(var, self.ev.fit((current[0] + step[0], current[1] + step[1]), ty), state)
        return state

    def call_effects(self, call: n.Call, state: State) -> None:
        info = self.facts.call(call)
        if info is None:
            return
        if getattr(info, "oo", ""):
            state.clear()   # a METHOD may write any variable of its instance (ours too) and globals
            return
        for var, value in info.inputs:
            if var.section == IN_OUT:
                self.kill_place(value, state)
        for var, target, _negate in info.outputs:
            self.write(target, None, state)
        if info.is_fb and info.instance is not None:
            key = place_key(info.instance, self.facts)
            if key is not None:
                self.kill_children(state, key)
        if not info.pou.native:
            # a user POU may write globals (VAR_EXTERNAL) and, through them, our in-outs
            for key in list(state):
                root = key.split(".", 1)[0].split("[", 1)[0]
                if self.sections.get(root, GLOBAL) in (GLOBAL, EXTERNAL, IN_OUT):
                    del state[key]

    def kill_place(self, target: n.Expr, state: State) -> None:
        key = place_key(target, self.facts)
        if key is not None:
            self.kill_children(state, key)
            state.pop(key, None)
            return
        base = root_expr(target)
        key = place_key(base, self.facts)
        if key is not None:
            self.kill_children(state, key)
            state.pop(key, None)

    def write(self, target: n.Expr, value: Interval | None, state: State) -> None:
        key = place_key(target, self.facts)
        if key is None:
            self.kill_place(target, state)
            return
        self.kill_children(state, key)
        ty = self.facts.type_of(target)
        if value is not None:
            value = self.ev.fit(value, ty)
            declared = self.ev.default(key, ty)
            if declared is not None:
                self.limits[key] = declared
            if isinstance(ty, t.StringType):
                self.string_keys.add(key)
            if value is not None and declared is not None and not isinstance(ty, t.StringType):
                value = meet(value, declared) or declared
        if value is None:
            state.pop(key, None)
        else:
            self.store(state, key, value)

    def store(self, state: State, key: str, value: Interval) -> None:
        state[key] = value
        if "." in key or "[" in key:
            for i, ch in enumerate(key):
                if ch in ".[":
                    self.parents.add(key[:i])

    def kill_children(self, state: State, key: str) -> None:
        if key in self.parents:
            _kill_prefix(state, key)

    # ---- edges
    def edge(self, edge: Edge, state: State) -> State | None:
        label = edge.label
        if label is None:
            return state
        kind = label[0]
        if kind in ("true", "false"):
            return self.refine(label[1], kind == "true", state)
        if kind in ("case", "else"):
            return self.refine_case(edge.src.expr, label[1], kind == "case", state)  # type: ignore[arg-type]
        if kind in ("for_in", "for_out"):
            return self.refine_for(label[1], kind == "for_in", state)
        return state

    def refine(self, cond: n.Expr, truth: bool, state: State) -> State | None:
        value = self.ev.eval(cond, state)
        want = 1 if truth else 0
        if value is not None and not value[0] <= want <= value[1]:
            return None
        if isinstance(cond, n.Unary) and cond.op == "NOT":
            return self.refine(cond.operand, not truth, state)
        if isinstance(cond, n.Binary):
            op = cond.op
            if op in ("AND", "AMP", "OR") and isinstance(self.facts.type_of(cond), t.BoolType):
                both = (op == "OR") != truth   # AND-true / OR-false: both sides hold
                if both:
                    first = self.refine(cond.left, truth, state)
                    return self.refine(cond.right, truth, first) if first is not None else None
                left = self.refine(cond.left, truth, state)
                right = self.refine(cond.right, truth, state)
                if left is None:
                    return right
                if right is None:
                    return left
                return self.join(left, right)
            if op in ("EQ", "NE", "LT", "GT", "LE", "GE"):
                return self.refine_compare(cond, truth, state)
            return state
        if isinstance(cond, (n.Name, n.Member, n.Index)) and isinstance(self.facts.type_of(cond), t.BoolType):
            key = place_key(cond, self.facts)
            if key is None:
                return state
            out = dict(state)
            self.store(out, key, (want, want))
            if truth and isinstance(cond, n.Member) and cond.name.lower() in _EXCLUSIVE_OUTPUTS:
                base = place_key(cond.base, self.facts)
                if base is not None and isinstance(self.facts.type_of(cond.base), t.FBType):
                    for sibling in _EXCLUSIVE_OUTPUTS:
                        if sibling != cond.name.lower() and self._has_pin(cond.base, sibling):
                            self.store(out, f"{base}.{sibling}", (0, 0))
            return out
        return state

    def _has_pin(self, instance: n.Expr, pin: str) -> bool:
        ty = self.facts.type_of(instance)
        pou = self.facts.pou(ty.qualname) if isinstance(ty, t.FBType) else None
        var = pou.variables.get(pin) if pou is not None else None
        return var is not None and var.section == OUTPUT and isinstance(var.type, t.BoolType)

    def refine_compare(self, cond: n.Binary, truth: bool, state: State) -> State | None:
        op = cond.op
        if not truth:
            op = {"EQ": "NE", "NE": "EQ", "LT": "GE", "GE": "LT", "GT": "LE", "LE": "GT"}[op]
        if isinstance(self.facts.operand_type(cond), t.RealType):
            return state
        out = state
        for place, other, flipped in ((cond.left, cond.right, False), (cond.right, cond.left, True)):
            subject, key = self._subject(place)
            if key is None:
                continue
            bound = self.ev.eval(other, out)
            current = self.ev.eval(subject, out) if subject is not place else self.ev.eval(place, out)
            if bound is None or current is None:
                continue
            rel = {"LT": "GT", "GT": "LT", "LE": "GE", "GE": "LE"}.get(op, op) if flipped else op
            limit = {"LT": (None, bound[1] - 1), "LE": (None, bound[1]), "GT": (bound[0] + 1, None),
                     "GE": (bound[0], None), "EQ": (bound[0], bound[1]), "NE": (None, None)}[rel]
            lo = current[0] if limit[0] is None else max(current[0], limit[0])
            hi = current[1] if limit[1] is None else min(current[1], limit[1])
            excluded = None
            if rel == "NE" and is_point(bound):
                if lo == bound[0]:
                    lo += 1
                if hi == bound[0]:
                    hi -= 1
                if lo < bound[0] < hi:
                    # an interval has no holes: remember the excluded value beside it
                    # (`x[<>0]`; a write of x drops it with x's other sub-keys)
                    excluded = excluded_key(key, bound[0])
            if lo > hi:
                return None
            if (lo, hi) != current or excluded is not None:
                out = dict(out)
                self.store(out, key, (lo, hi))
                if excluded is not None:
                    self.store(out, excluded, (1, 1))
        return out

    def _subject(self, expr: n.Expr) -> tuple[n.Expr, str | None]:
        """The place a comparison operand constrains: a variable, or the string of `LEN(s)`."""
        if isinstance(expr, n.Call):
            info = self.facts.call(expr)
            if info is not None and not info.is_fb and info.pou.name.upper() == "LEN" and info.inputs:
                inner = info.inputs[0][1]
                return inner, place_key(inner, self.facts)
            return expr, None
        if isinstance(self.facts.type_of(expr), (t.IntType, t.EnumType, t.BoolType)):
            return expr, place_key(expr, self.facts)
        return expr, None

    def refine_case(self, selector: n.Expr, labels: tuple, is_element: bool, state: State) -> State | None:
        key = place_key(selector, self.facts)
        current = self.ev.eval(selector, state)
        ranges = []
        for label in labels:
            lo = self.facts.const(label.low)
            hi = self.facts.const(label.high) if label.high is not None else lo
            if isinstance(lo, int) and isinstance(hi, int):
                ranges.append((lo, hi))
        if current is None:
            return state
        if is_element:
            hits = [meet(current, r) for r in ranges]
            hits = [h for h in hits if h is not None]
            if not hits:
                return None
            new = (min(h[0] for h in hits), max(h[1] for h in hits))
            if key is None or new == current:
                return state
            out = dict(state)
            self.store(out, key, new)
            return out
        # ELSE: remove labels covering an end of the interval
        lo, hi = current
        changed = True
        while changed and lo <= hi:
            changed = False
            for r_lo, r_hi in ranges:
                if r_lo <= lo <= r_hi:
                    lo, changed = r_hi + 1, True
                if r_lo <= hi <= r_hi:
                    hi, changed = r_lo - 1, True
        if lo > hi:
            return None
        if key is None or (lo, hi) == current:
            return state
        out = dict(state)
        self.store(out, key, (lo, hi))
        return out

    def refine_for(self, loop: n.For, inside: bool, state: State) -> State | None:
        step = self.ev.eval(loop.step, state) if loop.step is not None else (1, 1)
        if step is None or (step[0] <= 0 <= step[1]):
            return state
        op = ("LE" if step[0] > 0 else "GE") if inside else ("GT" if step[0] > 0 else "LT")
        return self._refine_loop_var(loop, op, state)

    def _refine_loop_var(self, loop: n.For, op: str, state: State) -> State | None:
        key = place_key(loop.variable, self.facts)
        current = self.ev.eval(loop.variable, state)
        bound = self.ev.eval(loop.end, state)
        if key is None or current is None or bound is None:
            return state
        lo, hi = current
        if op == "LE":
            hi = min(hi, bound[1])
        elif op == "GE":
            lo = max(lo, bound[0])
        elif op == "GT":
            lo = max(lo, bound[0] + 1)
        else:
            hi = min(hi, bound[1] - 1)
        if lo > hi:
            # the loop variable cannot pass the end without wrapping: exit only at the type's end
            return None
        out = dict(state)
        self.store(out, key, (lo, hi))
        return out


def _decimal_digits(iv: Interval, shortest: bool = False) -> int:
    """Length of the decimal text of the longest (or shortest) value of an interval."""
    def width(v: int) -> int:
        return len(str(v))
    if shortest:
        if iv[0] <= 0 <= iv[1]:
            return 1
        return min(width(iv[0]), width(iv[1]))
    return max(width(iv[0]), width(iv[1]))


def excluded_key(key: str, value: int) -> str:
    """The state key recording that place `key` is known to differ from `value`."""
    return f"{key}[<>{value}]"


def _kill_prefix(state: State, key: str) -> None:
    dotted, indexed = key + ".", key + "["
    for other in [k for k in state if k.startswith(dotted) or k.startswith(indexed)]:
        del state[other]


def _initial(var, settings) -> Interval | None:
    ty = var.type
    value = var.init
    if isinstance(ty, t.BoolType):
        v = int(bool(value)) if value is not None else 0
        return (v, v)
    if isinstance(ty, t.IntType):
        v = value if isinstance(value, int) else 0
        return (v, v)
    if isinstance(ty, t.EnumType):
        if isinstance(value, int):
            return (value, value)
        if ty.default is not None:
            return (ty.default, ty.default)
        if settings.enum_default is EnumDefault.ZERO:
            return (0, 0)
        return (ty.members[0][1],) * 2 if ty.members else None
    if isinstance(ty, t.StringType):
        size = len(value) if isinstance(value, bytes) else 0
        return (size, size)
    return None


def declared_subranges(pou: n.POU, alias_ranges: dict[str, Interval]) -> dict[str, Interval]:
    """Variables declared with a subrange (`x : INT(0..100)`, or a type alias of one): their
    narrower range. `alias_ranges`: lower-case type name (short or qualified) → range."""
    out: dict[str, Interval] = {}
    for block in pou.var_blocks:
        for decl in block.decls:
            spec = decl.type_spec
            rng = None
            if isinstance(spec, n.SubrangeTypeSpec):
                rng = (spec.low, spec.high)
            elif isinstance(spec, n.NamedTypeSpec):
                rng = alias_ranges.get("\\".join(spec.parts).lower())
            if rng is not None:
                for name, _ in decl.names:
                    out[name.lower()] = rng
    return out


def _statements_in(stmt) -> list:
    """A statement and every statement nested in it."""
    out = [stmt]
    if isinstance(stmt, n.If):
        for _, body in stmt.branches:
            for inner in body:
                out += _statements_in(inner)
        for inner in stmt.else_body or ():
            out += _statements_in(inner)
    elif isinstance(stmt, n.Case):
        for _, body in stmt.elements:
            for inner in body:
                out += _statements_in(inner)
        for inner in stmt.else_body or ():
            out += _statements_in(inner)
    elif isinstance(stmt, (n.For, n.While, n.Repeat)):
        for inner in stmt.body:
            out += _statements_in(inner)
    return out


def _assigned_roots(cfg: CFG, facts: FactsView) -> set[str]:
    """Variables some statement of the body writes (assignment, output binding, in-out, FOR)."""
    return {access.var.key for node in cfg.nodes for access in node_accesses(node, facts)
            if access.kind != "read"}


def _thresholds(cfg: CFG, facts: FactsView) -> list[int]:
    values = {0, 1, -1}
    for node in cfg.nodes:
        for sub in node_subexprs(node):
            value = facts.const(sub)
            if isinstance(value, int) and not isinstance(value, bool):
                values.update((value - 1, value, value + 1))
    for ty in t.ELEMENTARY.values():
        if isinstance(ty, t.IntType):
            values.update((ty.lo, ty.hi))
    values.update((0, MAX_STRING_BYTES))
    return sorted(values)


def analyze_ranges(cfg: CFG, pou_info, facts: FactsView, settings,
                   alias_ranges: dict[str, Interval] | None = None) -> tuple[RangeAnalysis, Solution]:
    analysis = RangeAnalysis(cfg, pou_info, facts, settings, alias_ranges)
    return analysis, solve(cfg, analysis, record_edges=True, narrow=2)
