"""SA4xx: control flow — CASE coverage, branches that never run, overwritten state, loops, REAL =."""

from __future__ import annotations

from stvm.lint.access import node_accesses
from stvm.lint.context import PouContext
from stvm.lint.facts_view import node_subexprs, iter_exprs, place_key, text_of
from stvm.lint.intervals import fmt
from stvm.lint.findings import rule
from stvm.semantics import types as t
from stvm.syntax import nodes as n


def _all_statements(body):
    for stmt in body:
        yield stmt
        if isinstance(stmt, n.If):
            for _, inner in stmt.branches:
                yield from _all_statements(inner)
            if stmt.else_body:
                yield from _all_statements(stmt.else_body)
        elif isinstance(stmt, n.Case):
            for _, inner in stmt.elements:
                yield from _all_statements(inner)
            if stmt.else_body:
                yield from _all_statements(stmt.else_body)
        elif isinstance(stmt, (n.For, n.While, n.Repeat)):
            yield from _all_statements(stmt.body)


@rule("SA401", "case-enum-incomplete",
      "a CASE on an enumeration has no ELSE and leaves enumerators unhandled",
      """
      When the selector holds an enumerator that no label lists and there is no ELSE, the CASE
      does nothing, silently. That is usually a state added to the enumeration later and forgotten
      here. List every enumerator, or add an ELSE that reports the unexpected value.
      """,
      """
      TYPE eMode : (Idle, Run, Fault); END_TYPE
      FUNCTION_BLOCK Machine
      VAR_INPUT mode : eMode; END_VAR
      VAR_OUTPUT lamp : BOOL; END_VAR
      CASE mode OF
          Idle: lamp := FALSE;
          Run:  lamp := TRUE;
      END_CASE;                       (* Fault: lamp keeps its value *)
      END_FUNCTION_BLOCK
      """,
      """
      TYPE eMode : (Idle, Run, Fault); END_TYPE
      FUNCTION_BLOCK Machine
      VAR_INPUT mode : eMode; END_VAR
      VAR_OUTPUT lamp : BOOL; END_VAR
      CASE mode OF
          Idle, Fault: lamp := FALSE;
          Run:  lamp := TRUE;
      END_CASE;
      END_FUNCTION_BLOCK
      """)
def case_enum_incomplete(ctx: PouContext):
    for stmt in _all_statements(ctx.node.body):
        if not isinstance(stmt, n.Case) or stmt.else_body is not None:
            continue
        sel = ctx.type_of(stmt.selector)
        if not isinstance(sel, t.EnumType):
            continue
        covered: set[int] = set()
        for labels, _ in stmt.elements:
            for label in labels:
                lo = ctx.facts.const(label.low)
                hi = ctx.facts.const(label.high) if label.high is not None else lo
                if isinstance(lo, int) and isinstance(hi, int):
                    covered.update(range(lo, hi + 1))
        missing = [name for name, value in sel.members if value not in covered]
        if missing:
            shown = ", ".join(missing[:6]) + (", …" if len(missing) > 6 else "")
            yield ctx.finding("SA401", f"CASE on {sel.name} has no ELSE and does not handle {shown}: "
                                       f"for {'it' if len(missing) == 1 else 'them'} nothing runs",
                              stmt.selector.span)


@rule("SA402", "dead-branch",
      "an IF/ELSIF or CASE branch can never run: its condition is constant on every path here",
      """
      A condition that is always FALSE (or a CASE label the selector can never hold) marks code
      that never runs; a condition that is always TRUE makes the following ELSIF/ELSE dead. On a
      controller this is usually a wrong comparison, a wrong variable, or a state that is never
      entered. The ranges come from the declarations, the values the POU assigns (for an FB,
      across scans) and the enclosing conditions.
      """,
      """
      FUNCTION_BLOCK Level
      VAR_INPUT raw : USINT; END_VAR
      VAR_OUTPUT alarm : BOOL; END_VAR
      IF raw > 300 THEN               (* a USINT is at most 255 *)
          alarm := TRUE;
      END_IF;
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Level
      VAR_INPUT raw : UINT; END_VAR
      VAR_OUTPUT alarm : BOOL; END_VAR
      IF raw > 300 THEN
          alarm := TRUE;
      END_IF;
      END_FUNCTION_BLOCK
      """)
def dead_branch(ctx: PouContext):
    feasible = ctx.feasible_edges
    for node, state in ctx.reachable_nodes():
        if node.kind == "branch" and isinstance(node.stmt, n.If):
            taken = {edge.label[0]: id(edge) in feasible for edge in node.succs if edge.label}
            cond = node.expr
            if not taken.get("true", True):
                value = ctx.value(cond, ctx.ranges.transfer(node, state))
                why = _why(ctx, cond, ctx.ranges.transfer(node, state))
                yield ctx.finding("SA402", f"this condition is always FALSE here{why}: its branch never runs"
                                  if value == (0, 0) else
                                  f"this branch can never run: {text_of(cond)} cannot hold here{why}", cond.span)
            elif not taken.get("false", True):
                later = _later_branches(node.stmt, cond)
                if later:
                    why = _why(ctx, cond, ctx.ranges.transfer(node, state))
                    yield ctx.finding("SA402", f"this condition is always TRUE here{why}: the {later} after it "
                                               f"never runs", cond.span)
        elif node.kind == "case":
            for edge in node.succs:
                if edge.label and edge.label[0] == "case" and id(edge) not in feasible and edge.label[1]:
                    rng = ctx.value(node.expr, ctx.ranges.transfer(node, state))
                    labels = edge.label[1]
                    yield ctx.finding("SA402", f"this CASE branch never runs: {text_of(node.expr)} is "
                                               f"{fmt(rng) if rng else 'never that'} here", labels[0].span)


def _later_branches(stmt: n.If, cond: n.Expr) -> str:
    index = next(i for i, (c, _) in enumerate(stmt.branches) if c is cond)
    if index + 1 < len(stmt.branches):
        return "ELSIF" + (" and ELSE" if stmt.else_body is not None else "")
    return "ELSE" if stmt.else_body is not None else ""


def _why(ctx: PouContext, cond: n.Expr, state) -> str:
    parts = []
    for sub in iter_exprs(cond):
        if isinstance(sub, (n.Name, n.Member)) and not isinstance(ctx.type_of(sub), (t.FBType, t.StructType)):
            if ctx.facts.const(sub) is not None and place_key(sub, ctx.facts) is not None:
                rng = ctx.value(sub, state)
                if rng is not None and isinstance(ctx.type_of(sub), (t.IntType, t.EnumType)):
                    parts.append(f"{text_of(sub)} is {fmt(rng)}")
                elif rng is not None and isinstance(ctx.type_of(sub), t.BoolType) and rng[0] == rng[1]:
                    parts.append(f"{text_of(sub)} is {'TRUE' if rng[0] else 'FALSE'}")
    return f" ({', '.join(dict.fromkeys(parts))})" if parts else ""


def _state_variables(ctx: PouContext) -> dict[str, object]:
    """Variables used as a CASE selector: the steps of a sequence."""
    out = {}
    for stmt in _all_statements(ctx.node.body):
        if isinstance(stmt, n.Case) and isinstance(stmt.selector, n.Name):
            var = ctx.facts.variable_of(stmt.selector)
            if var is not None:
                out[var.key] = var
    return out


@rule("SA403", "state-overwritten",
      "a state (step) variable is assigned, then assigned again on every path before anything reads it",
      """
      In a step sequence (`CASE step OF …`), a transition `step := 70` that a later `step := 40`
      of the same scan overwrites on every path never takes effect: the later write wins. Either
      the first transition is dead code or, more often, an `ELSE`/`RETURN` is missing and the
      sequence goes to the wrong step.
      """,
      """
      FUNCTION_BLOCK Seq
      VAR_INPUT ok : BOOL; END_VAR
      VAR step : INT; END_VAR
      CASE step OF
          0:  step := 10;
          10: IF ok THEN
                  step := 70;         (* overwritten below *)
              END_IF;
              step := 40;
      END_CASE;
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Seq
      VAR_INPUT ok : BOOL; END_VAR
      VAR step : INT; END_VAR
      CASE step OF
          0:  step := 10;
          10: IF ok THEN
                  step := 70;
              ELSE
                  step := 40;
              END_IF;
      END_CASE;
      END_FUNCTION_BLOCK
      """,
      thesis="`FB_step:=70` (valid data format) replaced by `FB_step:=40` in step 35 of CBT_MoveAbsolute and "
             "CBT_MoveRelative (st_src/README.md '+' rows; CBT_MoveAbsolute.st:398, 411 → 419).")
def state_overwritten(ctx: PouContext):
    states = _state_variables(ctx)
    if not states:
        return
    feasible = ctx.feasible_edges
    uses: dict[int, set[str]] = {}
    defs: dict[int, set[str]] = {}
    for node in ctx.cfg.nodes:
        u, d = set(), set()
        for access in node_accesses(node, ctx.facts):
            key = access.var.key
            if key not in states:
                continue
            if access.kind == "write":
                if key not in u:
                    d.add(key)
            else:
                u.add(key)
        uses[node.index], defs[node.index] = u, d
    persistent = set(states) if ctx.info.kind != "FUNCTION" else set()
    live_in: dict[int, set[str]] = {node.index: set() for node in ctx.cfg.nodes}
    live_in[ctx.cfg.exit.index] = set(persistent)
    order = list(reversed(ctx.cfg.rpo()))
    changed = True
    while changed:
        changed = False
        for node in order:
            if node is ctx.cfg.exit:
                continue
            out = set()
            for edge in node.succs:
                if id(edge) in feasible:
                    out |= live_in[edge.dst.index]
            new = (out - defs[node.index]) | uses[node.index]
            if new != live_in[node.index]:
                live_in[node.index] = new
                changed = True
    for node, _state in ctx.reachable_nodes():
        if node.kind != "assign" or not defs[node.index]:
            continue
        key = next(iter(defs[node.index]))
        live_out = set()
        for edge in node.succs:
            if id(edge) in feasible:
                live_out |= live_in[edge.dst.index]
        if key in live_out:
            continue
        later = _next_write(ctx, node, key, feasible)
        if later is not None and later.kind == "for_init":
            where = f" by FOR {text_of(later.stmt.variable)} := {text_of(later.stmt.start)} (line {later.stmt.span.line})"
        elif later is not None:
            where = f" by {text_of(later.stmt.target)} := {text_of(later.stmt.value)} (line {later.stmt.span.line})"
        else:
            where = ""
        yield ctx.finding("SA403", f"{text_of(node.stmt.target)} := {text_of(node.stmt.value)} is overwritten"
                                   f"{where} before anything reads it: the later write wins", node.stmt.span)


def _next_write(ctx: PouContext, start, key: str, feasible):
    seen = {start.index}
    frontier = [e.dst for e in start.succs if id(e) in feasible]
    while frontier:
        nxt = []
        for node in frontier:
            if node.index in seen:
                continue
            seen.add(node.index)
            if node.kind in ("assign", "for_init") and any(a.kind == "write" and a.var.key == key
                                                           for a in node_accesses(node, ctx.facts)):
                return node
            nxt += [e.dst for e in node.succs if id(e) in feasible]
        frontier = nxt
    return None


@rule("SA404", "for-variable-written",
      "a FOR loop's control variable is assigned in the loop body",
      """
      IEC 61131-3 forbids changing the control variable inside a FOR body; controllers differ in
      what they do, and the loop no longer runs the number of times its header says (or never ends).
      Use a WHILE loop when the iteration needs to jump.
      """,
      """
      FUNCTION_BLOCK Scan
      VAR data : ARRAY[0..9] OF INT; i : INT; END_VAR
      FOR i := 0 TO 9 DO
          IF data[i] = 0 THEN
              i := i + 1;             (* skips the next element *)
          END_IF;
      END_FOR;
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Scan
      VAR data : ARRAY[0..9] OF INT; i : INT; END_VAR
      i := 0;
      WHILE i <= 9 DO
          IF data[i] = 0 THEN
              i := i + 1;
          END_IF;
          i := i + 1;
      END_WHILE;
      END_FUNCTION_BLOCK
      """)
def for_variable_written(ctx: PouContext):
    by_stmt = {}
    for node in ctx.cfg.nodes:
        if node.stmt is not None:
            by_stmt.setdefault(node.stmt.nid, []).append(node)
    for stmt in _all_statements(ctx.node.body):
        if not isinstance(stmt, n.For):
            continue
        var = ctx.facts.variable_of(stmt.variable)
        if var is None:
            continue
        for inner in _all_statements(stmt.body):
            for node in by_stmt.get(inner.nid, []):
                if node.kind in ("for_init", "for_step"):
                    if node.kind == "for_init" and inner.variable is not None and \
                            ctx.facts.variable_of(inner.variable) is var:
                        yield ctx.finding("SA404", f"the inner FOR reuses '{var.name}', the control variable of "
                                                   f"the loop at line {stmt.span.line}", inner.variable.span)
                    continue
                for access in node_accesses(node, ctx.facts):
                    if access.var is var and access.kind != "read":
                        yield ctx.finding("SA404", f"'{var.name}', the control variable of the FOR at line "
                                                   f"{stmt.span.line}, is changed in its body", access.expr.span)


@rule("SA405", "real-equality",
      "REAL or LREAL values are compared with = or <>",
      """
      Binary floating point rarely gives exactly the value written in decimal: 0.1 + 0.2 is not
      0.3 in REAL, and a position computed by interpolation is never exactly the target. An
      equality test then fails (or `<>` succeeds) where the author expected the opposite. Compare
      with a tolerance: `ABS(a - b) < 0.001`. `x <> x` (the NaN test) is not reported. `x <> x` (the NaN test) is not reported.
      """,
      """
      FUNCTION_BLOCK AtTarget
      VAR_INPUT pos, target : REAL; END_VAR
      VAR_OUTPUT reached : BOOL; END_VAR
      reached := pos = target;
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK AtTarget
      VAR_INPUT pos, target : REAL; END_VAR
      VAR_OUTPUT reached : BOOL; END_VAR
      reached := ABS(pos - target) < 0.01;
      END_FUNCTION_BLOCK
      """)
def real_equality(ctx: PouContext):
    for node, _state in ctx.reachable_nodes():
        for sub in node_subexprs(node):
            if isinstance(sub, n.Binary) and sub.op in ("EQ", "NE") \
                    and isinstance(ctx.facts.operand_type(sub), t.RealType) and sub.left != sub.right:
                op = "=" if sub.op == "EQ" else "<>"
                yield ctx.finding("SA405", f"{text_of(sub)} compares {ctx.facts.operand_type(sub).name} values "
                                           f"with {op}: use a tolerance, ABS(a - b) < eps", sub.span)
