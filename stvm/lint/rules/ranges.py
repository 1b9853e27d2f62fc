"""SA2xx: ranges — array indices, integer overflow, narrowing conversions, division by zero.

All four read the interval analysis (stvm.lint.intervals): the value ranges at the statement,
from declarations, subranges, assignments, loop bounds and the conditions on the path.
"""

from __future__ import annotations

from stvm.lint.context import PouContext
from stvm.lint.facts_view import node_calls, node_subexprs, NOT_CONST, place_key, text_of
from stvm.lint.intervals import excluded_key, fmt, type_range
from stvm.lint.findings import rule
from stvm.semantics import types as t
from stvm.settings import ToarybyteStringModel
from stvm.syntax import nodes as n


def _linear(expr: n.Expr, ctx: PouContext) -> tuple[str | None, int] | None:
    """expr as (term, offset): a variable ('i', 3), LEN of a string ('len:s', -1), a constant
    (None, 5); None when it is none of these."""
    value = ctx.facts.const(expr)
    if isinstance(value, int) and not isinstance(value, bool):
        return (None, value)
    if isinstance(expr, (n.Name, n.Member)):
        key = place_key(expr, ctx.facts)
        return (key, 0) if key is not None else None
    if isinstance(expr, n.Call):
        info = ctx.facts.call(expr)
        if info is not None and not info.is_fb and info.pou.name.upper() == "LEN" and info.inputs:
            key = place_key(info.inputs[0][1], ctx.facts)
            return (f"len:{key}", 0) if key is not None else None
        return None
    if isinstance(expr, n.Binary) and expr.op in ("PLUS", "MINUS"):
        a, b = _linear(expr.left, ctx), _linear(expr.right, ctx)
        if a is None or b is None:
            return None
        sign = 1 if expr.op == "PLUS" else -1
        if b[0] is None:
            return (a[0], a[1] + sign * b[1])
        if a[0] is None and expr.op == "PLUS":
            return (b[0], a[1] + b[1])
    return None


def _buffer_fills(ctx: PouContext) -> dict[str, tuple[str, int, n.Span, str]]:
    """Arrays a STRING is copied into with ToAryByte(s, …, arr[k]): array key → (string key,
    first element k, call span, string text)."""
    out = {}
    for node in ctx.cfg.nodes:
        for call in node_calls(node):
            info = ctx.facts.call(call)
            if info is None or info.is_fb or info.pou.name.upper() != "TOARYBYTE":
                continue
            args = {var.key: value for var, value in info.inputs}
            source, target = args.get("in"), args.get("aryout")
            if source is None or target is None or not isinstance(ctx.facts.type_of(source), t.StringType):
                continue
            if not isinstance(target, n.Index) or len(target.indices) != 1:
                continue
            first = ctx.facts.const(target.indices[0])
            array_key, string_key = place_key(target.base, ctx.facts), place_key(source, ctx.facts)
            if isinstance(first, int) and array_key is not None and string_key is not None:
                out.setdefault(array_key, (string_key, first, call.span, text_of(source)))
    return out


def _loops_over(ctx: PouContext):
    """(FOR statement, its body's CFG nodes) for every FOR of the POU."""
    by_loop: dict[int, list] = {}
    loops = {}
    for node in ctx.cfg.nodes:
        if node.kind == "for_test":
            loops[node.stmt.nid] = node.stmt
    for loop in loops.values():
        inner = {s.nid for s in _statements(loop.body)}
        by_loop[loop.nid] = [node for node in ctx.cfg.nodes if node.stmt is not None and node.stmt.nid in inner]
    return [(loops[k], v) for k, v in by_loop.items()]


def _statements(body):
    for stmt in body:
        yield stmt
        if isinstance(stmt, n.If):
            for _, inner in stmt.branches:
                yield from _statements(inner)
            if stmt.else_body:
                yield from _statements(stmt.else_body)
        elif isinstance(stmt, n.Case):
            for _, inner in stmt.elements:
                yield from _statements(inner)
            if stmt.else_body:
                yield from _statements(stmt.else_body)
        elif isinstance(stmt, (n.For, n.While, n.Repeat)):
            yield from _statements(stmt.body)


@rule("SA201", "index-out-of-bounds",
      "an array index can leave the array's bounds, or the data copied into it, given the loop bounds",
      """
      An index outside the declared bounds is a major fault on the controller (the task stops).
      The range of the index comes from the loop bounds, the conditions around the access and the
      values assigned to it. The same reasoning finds the classic off-by-one of byte buffers: a
      text copied with `ToAryByte(s, …, buf[0])` occupies `buf[0] … buf[LEN(s)-1]`, so a loop
      `FOR i := 1 TO LEN(s)` that reads `buf[i]` reads one element past the text (the
      terminating 16#00, or a stale byte, depending on the copy). An index whose only known
      range is its whole type (an unchecked input) is not reported.
      """,
      """
      FUNCTION_BLOCK Checksum
      VAR_INPUT text : STRING[64]; END_VAR
      VAR_OUTPUT cs : BYTE; END_VAR
      VAR buf : ARRAY[0..63] OF BYTE; i : UINT; END_VAR
      ToAryByte(text, _eBYTE_ORDER#_LOW_HIGH, buf[0]);
      cs := 0;
      FOR i := 1 TO LEN(text) DO      (* buf[LEN(text)] is past the text *)
          cs := cs XOR buf[i];
      END_FOR;
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Checksum
      VAR_INPUT text : STRING[64]; END_VAR
      VAR_OUTPUT cs : BYTE; END_VAR
      VAR buf : ARRAY[0..63] OF BYTE; i : UINT; END_VAR
      ToAryByte(text, _eBYTE_ORDER#_LOW_HIGH, buf[0]);
      cs := 0;
      FOR i := 0 TO LEN(text) - 1 DO
          cs := cs XOR buf[i];
      END_FOR;
      END_FUNCTION_BLOCK
      """,
      thesis="the checksum loop `FOR i:=1 TO LEN(str_Checksum_Calc)` of every command FB "
             "(st_src/README.md 8.1, sysmac.md 8.1; CBT_MoveAbsolute.st:475-476).")
def index_out_of_bounds(ctx: PouContext):
    reported: set[int] = set()
    # declared bounds, from the interval analysis
    for node, state in ctx.reachable_nodes():
        for sub in node_subexprs(node):
            if not isinstance(sub, n.Index) or ctx.facts.is_array_from_element(sub):
                continue
            base = ctx.type_of(sub.base)
            if not isinstance(base, t.ArrayType) or not base.dims:
                continue
            for ix, (lo, hi) in zip(sub.indices, base.dims):
                rng = ctx.value(ix, state)
                if rng is None or (lo <= rng[0] and rng[1] <= hi):
                    continue
                if rng == type_range(ctx.type_of(ix)) or sub.nid in reported:
                    continue
                reported.add(sub.nid)
                yield ctx.finding("SA201", f"index {text_of(ix)} can be {fmt(rng)} here, outside "
                                           f"{text_of(sub.base)}'s bounds {lo}..{hi}", ix.span)
    # the data a string copy left in a buffer
    fills = _buffer_fills(ctx)
    if not fills:
        return
    model = ctx.settings.toarybyte_string_model
    for loop, body_nodes in _loops_over(ctx):
        var_key = place_key(loop.variable, ctx.facts)
        end = _linear(loop.end, ctx)
        step = ctx.facts.const(loop.step) if loop.step is not None else 1
        if var_key is None or end is None or end[0] is None or not end[0].startswith("len:") \
                or not isinstance(step, int) or step <= 0:
            continue
        string_key = end[0][4:]
        for node in body_nodes:
            if ctx.state_at(node) is None:
                continue
            for sub in node_subexprs(node):
                if not isinstance(sub, n.Index) or len(sub.indices) != 1 or sub.nid in reported:
                    continue
                array_key = place_key(sub.base, ctx.facts)
                fill = fills.get(array_key or "")
                idx = _linear(sub.indices[0], ctx)
                if fill is None or idx is None or idx[0] != var_key or fill[0] != string_key:
                    continue
                past = end[1] + idx[1] - fill[1]     # how far the last index is past the text's last byte + 1
                if past < 0:
                    continue
                reported.add(sub.nid)
                byte = {ToarybyteStringModel.TEXT_NUL: "the terminating 16#00 ToAryByte adds",
                        ToarybyteStringModel.TEXT: "a stale byte",
                        ToarybyteStringModel.IMAGE: "the string's unused storage"}[model]
                last = (f"{fill[1]} + " if fill[1] else "") + f"LEN({fill[3]})" + (f" + {past}" if past else "")
                yield ctx.finding(
                    "SA201",
                    f"{text_of(sub)} reaches index {last} when {text_of(loop.variable)} reaches "
                    f"its end: past the LEN({fill[3]}) bytes that ToAryByte copied from element {fill[1]} "
                    f"(line {fill[2].line}); that element is {byte} (toarybyte_string_model={model.value})",
                    sub.span)


@rule("SA202", "integer-overflow",
      "an integer constant expression, or a variable's range times a constant, overflows its type",
      """
      Integer arithmetic wraps at the width the operation computes in (sysmac.md 2: the larger
      operand type; an untyped literal takes the other operand's type if it fits, else DINT).
      `Seconds * 1000000000` with a UINT `Seconds` is computed in DINT and wraps from 3 s on: the
      result is a wrong, possibly negative, time. The rule reports constant expressions that
      overflow, and products of a variable by a constant that leave the type: from the
      variable's known range; from its declared range when the product is computed in a wider
      type than the variable's (the UINT × DINT case) or the factor is at least 100. `x * 2` of
      an INT with no known range is not reported: it overflows only near the INT limits.
      """,
      """
      FUNCTION_BLOCK Timeout
      VAR_INPUT seconds : UINT; END_VAR
      VAR_OUTPUT expired : BOOL; END_VAR
      VAR t : TON; END_VAR
      t(IN := TRUE, PT := NanoSecToTime(seconds * 1000000000), Q => expired);
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Timeout
      VAR_INPUT seconds : UINT; END_VAR
      VAR_OUTPUT expired : BOOL; END_VAR
      VAR t : TON; END_VAR
      t(IN := TRUE, PT := NanoSecToTime(UINT_TO_LINT(seconds) * 1000000000), Q => expired);
      END_FUNCTION_BLOCK
      """,
      thesis="`NanoSecToTime(ConnectionTimeOut*100000000)` in CBT_Connect (st_src/README.md 8.7, "
             "sysmac.md 8.7; CBT_Connect.st:490).")
def integer_overflow(ctx: PouContext):
    ev = ctx.ranges.ev
    for node, state in ctx.reachable_nodes():
        for sub in node_subexprs(node):
            if not isinstance(sub, n.Binary) or sub.op not in ("PLUS", "MINUS", "STAR"):
                continue
            ty = ctx.type_of(sub)
            if not isinstance(ty, t.IntType):
                continue
            if ctx.facts.const(sub) is not NOT_CONST:
                continue   # folded by the checker: typed to fit
            exact = ev.math(sub, state)
            if exact is None or (ty.lo <= exact[0] and exact[1] <= ty.hi):
                continue
            left_const = ctx.facts.const(sub.left) is not NOT_CONST
            right_const = ctx.facts.const(sub.right) is not NOT_CONST
            if left_const and right_const:
                yield ctx.finding("SA202", f"{text_of(sub)} = {fmt(exact)} overflows {ty.name} "
                                           f"({ty.lo}..{ty.hi}): it wraps", sub.span)
                continue
            if sub.op != "STAR" or not (left_const or right_const):
                continue
            variable, constant = (sub.right, sub.left) if left_const else (sub.left, sub.right)
            rng = ctx.value(variable, state)
            factor = ctx.facts.const(constant)
            if rng is None or not isinstance(factor, int) or factor == 0:
                continue
            source = ctx.type_of(variable)
            derived = rng != type_range(source)
            widened = isinstance(source, t.IntType) and source.bits < ty.bits
            # Choice: a product computed in the variable's own type overflows only near its
            # limits (`x * 2`); that is reported when the range is known, or when the factor
            # is large (>= 100: from 1 % of the range on). A product computed in a wider type
            # than the variable's (UINT * DINT literal) is reported from the declared range:
            # the author meant the wider type to hold it.
            if not (derived or widened or abs(factor) >= 100):
                continue
            limit = ty.hi if factor > 0 else ty.lo
            first = -(-(limit + (1 if factor > 0 else -1)) // factor) if factor > 0 else None
            from_where = f"{source.name}" if rng == type_range(source) else "its range here"
            detail = f" from {text_of(variable)} = {first} on" if first is not None and rng[0] < first <= rng[1] else ""
            yield ctx.finding("SA202", f"{text_of(sub)} is computed in {ty.name}: with {text_of(variable)} "
                                       f"{fmt(rng)} ({from_where}) it reaches {fmt(exact)}, beyond "
                                       f"{ty.name}'s {ty.lo}..{ty.hi}, and wraps{detail}", sub.span)


def _implicit_conversions(ctx: PouContext, node):
    """(value expr, target type, what) of the implicit conversions a node performs."""
    stmt = node.stmt
    if node.kind == "assign":
        target = ctx.type_of(stmt.target)
        if target is not None:
            yield stmt.value, target, f"assigning to {text_of(stmt.target)}"
    for call in node_calls(node):
        info = ctx.facts.call(call)
        if info is None or info.pou.generic:
            continue
        for var, value in info.inputs:
            if var.section == "VAR_INPUT" and not isinstance(var.type, t.GenericType):
                yield value, var.type, f"passing it to {var.name} of {info.pou.name}"


@rule("SA203", "narrowing-conversion",
      "a conversion to a smaller or differently signed integer type can lose the value",
      """
      Sysmac converts same-size signed and unsigned integers implicitly (INT ↔ UINT), and a
      conversion function such as DINT_TO_INT keeps only the low bits: a value outside the target
      range silently becomes another number. The rule reports implicit sign changes whose value
      range does not fit the target, and explicit narrowing conversions whose argument's known
      range (not merely its type) does not fit.
      """,
      """
      FUNCTION_BLOCK Port
      VAR_INPUT port : INT; END_VAR
      VAR connect : SktTCPConnect; addr : STRING[20]; END_VAR
      connect(Execute := TRUE, SrcTcpPort := 0, DstAdr := addr, DstTcpPort := port);  (* -1 → 65535 *)
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Port
      VAR_INPUT port : UINT; END_VAR
      VAR connect : SktTCPConnect; addr : STRING[20]; END_VAR
      connect(Execute := TRUE, SrcTcpPort := 0, DstAdr := addr, DstTcpPort := port);
      END_FUNCTION_BLOCK
      """)
def narrowing_conversion(ctx: PouContext):
    for node, state in ctx.reachable_nodes():
        for value, target, what in _implicit_conversions(ctx, node):
            source = ctx.type_of(value)
            if not (isinstance(source, t.IntType) and isinstance(target, t.IntType)):
                continue
            if source.signed == target.signed or source.bits != target.bits:
                continue
            rng = ctx.value(value, state)
            if rng is None or (target.lo <= rng[0] and rng[1] <= target.hi):
                continue
            yield ctx.finding("SA203", f"{text_of(value)} ({source.name}, {fmt(rng)}) is converted to "
                                       f"{target.name} ({target.lo}..{target.hi}) {what}: values outside "
                                       f"that range change", value.span)
        for call in node_calls(node):
            info = ctx.facts.call(call)
            if info is None or info.is_fb or "_TO_" not in info.pou.name.upper() or not info.inputs:
                continue
            result = info.pou.return_type
            arg = info.inputs[0][1]
            source = ctx.type_of(arg)
            if not isinstance(result, t.IntType) or not isinstance(source, t.IntType):
                continue
            rng = ctx.value(arg, state)
            if rng is None or rng == type_range(source) or (result.lo <= rng[0] and rng[1] <= result.hi):
                continue
            yield ctx.finding("SA203", f"{info.pou.name}({text_of(arg)}): the argument can be {fmt(rng)} "
                                       f"here, outside {result.name} ({result.lo}..{result.hi})", call.span)


@rule("SA204", "division-by-zero",
      "an integer division or MOD whose divisor can be 0",
      """
      Integer division by zero is a major fault on the controller (sysmac.md 1: the task stops;
      `int_div_zero`). The divisor's range comes from its type, its known values and the
      conditions on the path: `IF d <> 0 THEN q := a / d; END_IF;` is not reported.
      """,
      """
      FUNCTION Average : INT
      VAR_INPUT total : INT; count : INT; END_VAR
      Average := total / count;
      END_FUNCTION
      """,
      """
      FUNCTION Average : INT
      VAR_INPUT total : INT; count : INT; END_VAR
      IF count <> 0 THEN
          Average := total / count;
      ELSE
          Average := 0;
      END_IF;
      END_FUNCTION
      """)
def division_by_zero(ctx: PouContext):
    for node, state in ctx.reachable_nodes():
        for sub in node_subexprs(node):
            if not isinstance(sub, n.Binary) or sub.op not in ("SLASH", "MOD"):
                continue
            if not isinstance(ctx.type_of(sub), t.IntType):
                continue
            rng = ctx.value(sub.right, state)
            if rng is None or not rng[0] <= 0 <= rng[1]:
                continue
            key = place_key(sub.right, ctx.facts)
            if key is not None and excluded_key(key, 0) in state:
                continue   # tested `<> 0` on this path
            op = "/" if sub.op == "SLASH" else "MOD"
            yield ctx.finding("SA204", f"divisor {text_of(sub.right)} can be 0 here ({fmt(rng)}): "
                                       f"{op} by zero stops the task", sub.right.span)
