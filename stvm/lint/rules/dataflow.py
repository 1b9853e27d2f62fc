"""SA1xx: data flow — reads before writes, dead writes, unassigned outputs, FB calls, Execute."""

from __future__ import annotations

from stvm.lint.access import RESULT, node_accesses
from stvm.lint.context import PouContext, solve_sets
from stvm.lint.facts_view import INPUT, LOCAL, OUTPUT, TEMP, place_key, text_of
from stvm.lint.findings import rule
from stvm.semantics import types as t
from stvm.syntax import nodes as n


def _explicit_inits(ctx: PouContext) -> set[str]:
    out = set()
    for block in ctx.node.var_blocks:
        for decl in block.decls:
            if decl.init is not None:
                out.update(name.lower() for name, _ in decl.names)
    return out


def _fresh_candidates(ctx: PouContext) -> dict[str, object]:
    """Variables that start from their initial value on every call: VAR_TEMP, and a FUNCTION's
    locals, outputs and result."""
    sections = (LOCAL, OUTPUT, TEMP) if ctx.info.kind == "FUNCTION" else (TEMP,)
    explicit = _explicit_inits(ctx)
    out = {key: var for key, var in ctx.info.variables.items()
           if var.section in sections and key not in explicit and not isinstance(var.type, t.FBType)}
    if ctx.info.kind == "FUNCTION":
        out[RESULT.key] = RESULT
    return out


def _must_assigned(ctx: PouContext, candidates: dict[str, object]):
    facts = ctx.facts

    def transfer(node, state):
        new = None
        for access in node_accesses(node, facts):
            if access.kind != "read" and access.var.key in candidates:
                if new is None:
                    new = set(state)
                new.add(access.var.key)
        return frozenset(new) if new is not None else state

    return solve_sets(ctx, frozenset(), transfer, must=True)


@rule("SA101", "read-before-write",
      "a temporary variable (or a function's local or result) is read on some path before any write",
      """
      VAR_TEMP variables, and every variable of a FUNCTION, start from their initial value on each
      call. Reading one before the body wrote it uses that initial value on the paths that skip the
      write, which is rarely what the author meant: the value looks computed but is a constant. A
      declaration with an explicit initial value (`x : INT := 0;`) states the intent and is not
      reported.
      """,
      """
      FUNCTION Scale : INT
      VAR_INPUT raw : INT; enable : BOOL; END_VAR
      VAR factor : INT; END_VAR
      IF enable THEN
          factor := 10;
      END_IF;
      Scale := raw * factor;      (* factor is 0 when enable is FALSE *)
      END_FUNCTION
      """,
      """
      FUNCTION Scale : INT
      VAR_INPUT raw : INT; enable : BOOL; END_VAR
      VAR factor : INT := 1; END_VAR
      IF enable THEN
          factor := 10;
      END_IF;
      Scale := raw * factor;
      END_FUNCTION
      """)
def read_before_write(ctx: PouContext):
    candidates = _fresh_candidates(ctx)
    if not candidates:
        return
    solution = _must_assigned(ctx, candidates)
    reported: set[str] = set()
    for node in ctx.cfg.nodes:
        state = solution.at(node)
        if state is None or ctx.state_at(node) is None:
            continue
        assigned = set(state)
        for access in node_accesses(node, ctx.facts):
            key = access.var.key
            if key not in candidates:
                continue
            if access.kind == "read" and key not in assigned and key not in reported:
                reported.add(key)
                name = ctx.info.name if access.var is RESULT else access.var.name
                what = "the function result" if access.var is RESULT else f"'{name}'"
                yield ctx.finding("SA101", f"{what} is read before it is written on some path "
                                           f"(it still holds its initial value there)", access.expr.span)
            elif access.kind != "read":
                assigned.add(key)


@rule("SA102", "unused-write",
      "a local variable of a function block or function is written but never read",
      """
      A value that is stored and never read is either dead code or a sign that the code reads
      the wrong variable. Typical on a controller: a receive block's `RcvSize=>` output is bound
      to a variable that nothing reads, while the code goes on using the requested size.
      Variables of a PROGRAM are not reported: the HMI, traces and `stvm run --print` read them.
      """,
      """
      FUNCTION_BLOCK Rx
      VAR_OUTPUT text : STRING[256]; END_VAR
      VAR rcv : SktTCPRcv; sock : _sSOCKET; buf : ARRAY[0..255] OF BYTE; received : UINT; END_VAR
      rcv(Execute := TRUE, Socket := sock, Size := 256, RcvDat := buf[0], RcvSize => received);
      text := AryToString(buf[0], 256);      (* received is never used *)
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Rx
      VAR_OUTPUT text : STRING[256]; END_VAR
      VAR rcv : SktTCPRcv; sock : _sSOCKET; buf : ARRAY[0..255] OF BYTE; received : UINT; END_VAR
      rcv(Execute := TRUE, Socket := sock, Size := 256, RcvDat := buf[0], RcvSize => received);
      text := AryToString(buf[0], received);
      END_FUNCTION_BLOCK
      """,
      thesis="`TCP_Rcv_RcvSize` in every command FB but CBT_Connect (st_src/README.md 8.3), `Length` in the move FBs.")
def unused_write(ctx: PouContext):
    if ctx.oo_shared:
        return   # its methods may read what the body writes
    if ctx.info.kind == "PROGRAM":
        sections = (TEMP,)
    else:
        sections = (LOCAL, TEMP)
    candidates = {key: var for key, var in ctx.info.variables.items()
                  if var.section in sections and not var.constant and not isinstance(var.type, t.FBType)}
    if not candidates:
        return
    first_write: dict[str, n.Span] = {}
    read: set[str] = set()
    for node in ctx.cfg.nodes:
        for access in node_accesses(node, ctx.facts):
            key = access.var.key
            if key not in candidates:
                continue
            if access.kind in ("read", "inout"):
                read.add(key)
            elif key not in first_write or _before(access.expr.span, first_write[key]):
                first_write[key] = access.expr.span
    for key, span in first_write.items():
        if key not in read:
            var = candidates[key]
            yield ctx.finding("SA102", f"'{var.name}' is written (line {span.line}) but never read", var.span)


def _before(a: n.Span, b: n.Span) -> bool:
    return (a.line, a.column) < (b.line, b.column)


@rule("SA103", "output-unassigned",
      "a function's result or output is not assigned on some path, or an FB output is never assigned",
      """
      A FUNCTION returns its result and outputs fresh on every call: a path that does not assign
      them returns the type's default (0, FALSE, ''), silently. An output of a FUNCTION_BLOCK keeps
      its value between calls, so an FB output is reported only when no statement of the body
      assigns it at all: the caller then reads a pin that never changes.
      """,
      """
      FUNCTION Sign : INT
      VAR_INPUT x : INT; END_VAR
      IF x > 0 THEN
          Sign := 1;
      ELSIF x < 0 THEN
          Sign := -1;
      END_IF;                     (* x = 0 returns 0 by accident *)
      END_FUNCTION
      """,
      """
      FUNCTION Sign : INT
      VAR_INPUT x : INT; END_VAR
      Sign := 0;
      IF x > 0 THEN
          Sign := 1;
      ELSIF x < 0 THEN
          Sign := -1;
      END_IF;
      END_FUNCTION
      """)
def output_unassigned(ctx: PouContext):
    if ctx.info.kind == "FUNCTION":
        explicit = _explicit_inits(ctx)
        candidates = {key: var for key, var in ctx.info.variables.items()
                      if var.section == OUTPUT and key not in explicit}
        if not isinstance(ctx.info.return_type, t.VoidType):
            candidates[RESULT.key] = RESULT
        if not candidates:
            return
        solution = _must_assigned(ctx, candidates)
        at_exit = solution.at(ctx.cfg.exit)
        if at_exit is None:
            return
        for key, var in candidates.items():
            if key not in at_exit:
                what = f"the result of {ctx.info.name}" if var is RESULT else f"output '{var.name}'"
                span = ctx.node.end_span if ctx.node.end_span.line else ctx.node.span
                pou_word = "method" if getattr(ctx, "method_of", "") else "function"
                yield ctx.finding("SA103", f"{what} is not assigned on some path through the {pou_word} "
                                           f"(it returns the type's default there)", span)
        return
    if ctx.info.kind != "FUNCTION_BLOCK" or ctx.oo_shared:
        return   # (an FB whose methods or base body may assign its outputs: not decidable here)
    outputs = {key: var for key, var in ctx.info.variables.items() if var.section == OUTPUT}
    written = set()
    for node in ctx.cfg.nodes:
        for access in node_accesses(node, ctx.facts):
            if access.kind != "read":
                written.add(access.var.key)
    for key, var in outputs.items():
        if key not in written:
            yield ctx.finding("SA103", f"output '{var.name}' of {ctx.info.name} is never assigned", var.span)


@rule("SA104", "fb-called-twice",
      "an FB instance is called more than once in one scan on some path",
      """
      An FB instance is a piece of state that advances once per call: a timer measures time
      between calls, an edge detector compares with its previous call, a PLCopen block starts on
      the rising edge of Execute between calls. Calling the same instance twice per scan (or in a
      loop) makes the second call see the first call's result as "previous": timers, edges and
      handshakes misbehave. Calls in exclusive branches are fine, and so is a reset call
      (`fb(Execute := FALSE)`, `IN`/`CLK` FALSE) followed by a new start: the PLCopen way to
      restart a block within one scan.
      """,
      """
      FUNCTION_BLOCK Delay
      VAR_INPUT start, fast : BOOL; END_VAR
      VAR_OUTPUT q : BOOL; END_VAR
      VAR t : TON; END_VAR
      t(IN := start, PT := T#1s);
      IF fast THEN
          t(IN := start, PT := T#100ms);   (* second call: the timer advances twice *)
      END_IF;
      q := t.Q;
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Delay
      VAR_INPUT start, fast : BOOL; END_VAR
      VAR_OUTPUT q : BOOL; END_VAR
      VAR t : TON; END_VAR
      t(IN := start, PT := SEL(fast, T#1s, T#100ms));
      q := t.Q;
      END_FUNCTION_BLOCK
      """)
def fb_called_twice(ctx: PouContext):
    facts = ctx.facts

    resets: set[int] = set()

    def instance_key(node):
        if node.kind != "call":
            return None
        call = node.stmt.call
        info = facts.call(call) if isinstance(call, n.Call) else None
        if info is None or not info.is_fb or info.instance is None:
            return None
        for var, value in info.inputs:
            if var.key in _START_PINS and facts.const(value) is False:
                resets.add(node.index)    # `fb(Execute := FALSE)`: the handshake's reset call
        return place_key(info.instance, facts)

    keys = {node.index: instance_key(node) for node in ctx.cfg.nodes}

    def transfer(node, state):
        key = keys[node.index]
        if key is None:
            return state
        # after a reset call the next call starts a new request: that is the PLCopen way to
        # restart an Execute-type block within one scan
        return state - {key} if node.index in resets else state | {key}

    solution = solve_sets(ctx, frozenset(), transfer, must=False)
    for node in ctx.cfg.nodes:
        key = keys[node.index]
        state = solution.at(node)
        if key is None or state is None or ctx.state_at(node) is None or node.index in resets:
            continue
        if key in state:
            yield ctx.finding("SA104", f"'{text_of(node.stmt.call.callee)}' may already have been called in "
                                       f"this scan (the second call sees the first one's result as its "
                                       f"previous call)", node.stmt.span)


_START_PINS = ("execute", "in", "clk", "enable")


def _execute_inputs(ctx: PouContext) -> set[str]:
    return {key for key, var in ctx.info.variables.items()
            if var.section == INPUT and isinstance(var.type, t.BoolType) and key.endswith("execute")}


def _positive_reads(expr: n.Expr, keys: set[str], ctx: PouContext, positive: bool = True):
    """Reads of the Execute inputs in `expr` where TRUE makes the condition more likely TRUE."""
    if isinstance(expr, n.Name):
        var = ctx.facts.variable_of(expr)
        if var is not None and var.key in keys and var.section == INPUT and positive:
            yield expr
    elif isinstance(expr, n.Unary) and expr.op == "NOT":
        yield from _positive_reads(expr.operand, keys, ctx, not positive)
    elif isinstance(expr, n.Binary) and expr.op in ("AND", "AMP", "OR"):
        yield from _positive_reads(expr.left, keys, ctx, positive)
        yield from _positive_reads(expr.right, keys, ctx, positive)
    elif isinstance(expr, n.Binary) and expr.op in ("EQ", "NE"):
        for side, other in ((expr.left, expr.right), (expr.right, expr.left)):
            value = ctx.facts.const(other)
            if isinstance(value, bool):
                yield from _positive_reads(side, keys, ctx, positive == (value == (expr.op == "EQ")))


@rule("SA105", "execute-level",
      "an Execute input starts an action on its level instead of its rising edge",
      """
      PLCopen function blocks start on the rising edge of `Execute` and keep their outputs until
      Execute falls (sysmac.md 4). A condition that is TRUE whenever Execute is TRUE acts again in
      every scan and in every state of the block, including after Done or Error. Use an R_TRIG on
      Execute to start, and `NOT Execute` to reset; passing Execute on to an inner block's Execute
      is fine (that block detects the edge).
      """,
      """
      FUNCTION_BLOCK MoveAxis
      VAR_INPUT Execute : BOOL; END_VAR
      VAR_OUTPUT Error : BOOL; END_VAR
      VAR_IN_OUT Axis : BOOL; END_VAR
      IF Execute AND NOT Axis THEN   (* raises Error in every scan and every state *)
          Error := TRUE;
      END_IF;
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK MoveAxis
      VAR_INPUT Execute : BOOL; END_VAR
      VAR_OUTPUT Error : BOOL; END_VAR
      VAR_IN_OUT Axis : BOOL; END_VAR
      VAR start : R_TRIG; END_VAR
      start(CLK := Execute);
      IF start.Q AND NOT Axis THEN
          Error := TRUE;
      ELSIF NOT Execute THEN
          Error := FALSE;
      END_IF;
      END_FUNCTION_BLOCK
      """,
      thesis="`IF Execute AND NOT(CBT.Connected)` at the top of every command FB raises 16#99 in any state "
             "(st_src/README.md, '+' rows; CBT_MoveAbsolute.st:115).")
def execute_level(ctx: PouContext):
    if ctx.info.kind != "FUNCTION_BLOCK":
        return
    keys = _execute_inputs(ctx)
    if not keys:
        return
    for node, _state in ctx.reachable_nodes():
        if node.kind != "branch" or node.expr is None or not isinstance(node.stmt, (n.If, n.While)):
            continue
        for read in _positive_reads(node.expr, keys, ctx):
            yield ctx.finding("SA105", f"'{read.text}' is read as a level here: this branch runs in every "
                                       f"scan while {read.text} is TRUE, not once on its rising edge",
                              read.span)
