"""SA3xx: formatting and protocol — hex text, decimals of positions, receive sizes, string sizes."""

from __future__ import annotations

from stvm.lint.context import PouContext
from stvm.lint.facts_view import node_calls, node_subexprs, iter_exprs, node_exprs, place_key, root_expr, text_of
from stvm.lint.intervals import MAX_STRING_BYTES, fmt, is_point
from stvm.lint.findings import rule
from stvm.semantics import types as t
from stvm.settings import ByteToStringFormat
from stvm.syntax import nodes as n

_HEX_DIGITS = {"BYTE": 2, "WORD": 4, "DWORD": 8, "LWORD": 16}
_RECEIVE_FBS = {"SKTTCPRCV": ("rcvdat", "size", "rcvsize"), "SKTUDPRCV": ("rcvdat", "size", "rcvsize")}
# identifiers that name a position or an orientation (robot poses, axes, coordinates)
_POSITION_NAMES = {"x", "y", "z", "rx", "ry", "rz", "a", "b", "c", "j1", "j2", "j3", "j4", "j5", "j6"}
_POSITION_WORDS = ("pos", "coord", "pose", "point", "target", "offset", "joint")


def _calls(ctx: PouContext):
    """(node, state, call, info) for every function/FB call in reachable statements."""
    for node, state in ctx.reachable_nodes():
        for call in node_calls(node):
            info = ctx.facts.call(call)
            if info is not None:
                yield node, state, call, info


def _parents(root: n.Expr) -> dict[int, n.Expr]:
    out: dict[int, n.Expr] = {}
    for expr in iter_exprs(root):
        if isinstance(expr, n.Call):
            for arg in expr.args:
                out[arg.value.nid] = expr
        elif isinstance(expr, n.Binary):
            out[expr.left.nid] = out[expr.right.nid] = expr
        elif isinstance(expr, n.Unary):
            out[expr.operand.nid] = expr
    return out


def _is_zero_text(expr: n.Expr, ctx: PouContext) -> bool:
    value = ctx.facts.const(expr)
    return isinstance(value, bytes) and value != b"" and set(value) == {ord("0")}


def _padded(call: n.Call, top: n.Expr, ctx: PouContext) -> bool:
    """Inside a CONCAT that puts literal '0'/'00' text before it (possibly cut with RIGHT)."""
    parents = _parents(top)
    child: n.Expr = call
    parent = parents.get(call.nid)
    while parent is not None:
        if isinstance(parent, n.Call):
            info = ctx.facts.call(parent)
            if info is not None and info.pou.name.upper() == "CONCAT":
                values = [a.value for a in parent.args]
                position = next((i for i, v in enumerate(values) if v is child), 0)
                if any(_is_zero_text(v, ctx) for v in values[:position]):
                    return True
        child, parent = parent, parents.get(parent.nid)
    return False


def _length_checked(ctx: PouContext) -> set[str]:
    """String places whose LEN the POU tests (a padding step follows)."""
    out = set()
    for node in ctx.cfg.nodes:
        for sub in node_subexprs(node):
            if isinstance(sub, n.Binary) and sub.op in ("EQ", "NE", "LT", "LE", "GT", "GE"):
                for side in (sub.left, sub.right):
                    info = ctx.facts.call(side) if isinstance(side, n.Call) else None
                    if info is not None and info.pou.name.upper() == "LEN" and info.inputs:
                        key = place_key(info.inputs[0][1], ctx.facts)
                        if key is not None:
                            out.add(key)
    return out


@rule("SA301", "hex-unpadded",
      "a byte (or word) is formatted to hex text without padding to its full width",
      """
      Sysmac's BYTE_TO_STRING writes hexadecimal without a leading zero (sysmac.md 6,
      `byte_to_string_format`): 16#0A becomes 'A'. A protocol that expects two hex digits —
      the TM Listen Node checksum `*CS` is "fixed to 2 bytes" — then receives one digit for
      1 value in 16, and rejects the frame ($CPERR). Pad the text: `RIGHT(CONCAT('0',
      BYTE_TO_STRING(cs)), 2)`, or test `LEN()` and prepend '0'. WORD/DWORD/LWORD_TO_STRING alike.
      Not reported when the value's range always has the full number of digits.
      """,
      """
      FUNCTION_BLOCK Frame
      VAR_INPUT cs : BYTE; END_VAR
      VAR_OUTPUT text : STRING[8]; END_VAR
      text := CONCAT('*', BYTE_TO_STRING(cs));     (* '*A' for 16#0A *)
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Frame
      VAR_INPUT cs : BYTE; END_VAR
      VAR_OUTPUT text : STRING[8]; END_VAR
      text := CONCAT('*', RIGHT(CONCAT('0', BYTE_TO_STRING(cs)), 2));
      END_FUNCTION_BLOCK
      """,
      thesis="`str_Checksum:=BYTE_TO_STRING(Send_Checksum[0])` in every command FB (st_src/README.md 8.2, "
             "ERRATA.md Q2, FIDELITY_FINDINGS 8.2; CBT_MoveAbsolute.st:480).")
def hex_unpadded(ctx: PouContext):
    style = ctx.settings.byte_to_string_format
    if style is ByteToStringFormat.HEX_PAD2:
        return
    checked = _length_checked(ctx)
    for node, state, call, info in _calls(ctx):
        name = info.pou.name.upper()
        source = name[: -len("_TO_STRING")] if name.endswith("_TO_STRING") else ""
        if source not in _HEX_DIGITS or not info.inputs:
            continue
        digits = _HEX_DIGITS[source]
        arg = info.inputs[0][1]
        rng = ctx.value(arg, state)
        full = 16 ** (digits - 1)
        if rng is not None and rng[0] >= full:
            continue
        top = next((e for e in node_exprs(node.stmt, node.kind, node.expr) if any(x is call for x in iter_exprs(e))), call)
        if _padded(call, top, ctx):
            continue
        if node.kind == "assign" and node.stmt.value is call and place_key(node.stmt.target, ctx.facts) in checked:
            continue
        form = "hexadecimal without leading zeros" if style is ByteToStringFormat.HEX_NOPAD else "decimal"
        example = "'A', not '0A'" if source == "BYTE" else "fewer digits"
        share = f"values below 16#{full:X}"
        if rng is not None and rng[1] < full:
            share = f"every value here ({fmt(rng)})"
        yield ctx.finding("SA301", f"{text_of(call)} writes {form} (byte_to_string_format={style.value}): "
                                   f"{share} give fewer than {digits} digits ({example})", call.span)


def _is_position(expr: n.Expr) -> str | None:
    names = []
    e = expr
    while True:
        if isinstance(e, n.Member):
            names.append(e.name)
            e = e.base
        elif isinstance(e, n.Index):
            e = e.base
        elif isinstance(e, n.Name):
            names.append(e.parts[-1])
            break
        else:
            return None
    for name in names:
        low = name.lower()
        if low in _POSITION_NAMES or any(word in low for word in _POSITION_WORDS):
            return name
    return None


@rule("SA302", "position-decimals",
      "a REAL that is a position or angle is formatted with 0 decimals",
      """
      RealToFormatString with `DecPlace := 0` rounds to a whole number: a robot target of
      417.5 mm is sent as +418, and every pose is quantised to 1 mm / 1 degree, far coarser than a
      cobot's repeatability (±0.03 mm on the TM5). The rule recognises positions by the names in
      the value's path (X, Y, Z, RX, RY, RZ, J1…J6, …Pos…, …Target…, …Offset…). Converting such a
      value with REAL_TO_INT (or ROUND/TRUNC) before formatting has the same effect.
      """,
      """
      FUNCTION_BLOCK Target
      VAR_INPUT TargetPosition : ARRAY[0..5] OF REAL; END_VAR
      VAR_OUTPUT text : STRING[32]; END_VAR
      text := RealToFormatString(In := TargetPosition[0], Exponent := FALSE, Sign := TRUE,
                                 MinLen := 1, DecPlace := 0);
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Target
      VAR_INPUT TargetPosition : ARRAY[0..5] OF REAL; END_VAR
      VAR_OUTPUT text : STRING[32]; END_VAR
      text := RealToFormatString(In := TargetPosition[0], Exponent := FALSE, Sign := TRUE,
                                 MinLen := 1, DecPlace := 3);
      END_FUNCTION_BLOCK
      """,
      thesis="the target poses of CBT_MoveAbsolute/Relative/Circle and the base and TCP values of "
             "CBT_ChangeBase/ChangeTCP (st_src/README.md 8.13, sysmac.md 8.13; CBT_MoveAbsolute.st:362-367).")
def position_decimals(ctx: PouContext):
    for node, state, call, info in _calls(ctx):
        name = info.pou.name.upper()
        if name == "REALTOFORMATSTRING":
            args = {var.key: value for var, value in info.inputs}
            value = args.get("in")
            if value is None:
                continue
            decimals = ctx.value(args["decplace"], state) if "decplace" in args else (6, 6)
            if decimals is None or decimals[1] != 0:
                continue
            position = _is_position(value)
            if position is None:
                continue
            yield ctx.finding("SA302", f"{text_of(value)} looks like a position ('{position}') and is formatted "
                                       f"with DecPlace 0: it is rounded to a whole number (0.5 mm and 0.5° "
                                       f"steps are lost)", call.span)
        elif name.endswith("_TO_STRING") and info.inputs:
            inner = info.inputs[0][1]
            inner_info = ctx.facts.call(inner) if isinstance(inner, n.Call) else None
            if inner_info is None or not inner_info.inputs:
                continue
            conv = inner_info.pou.name.upper()
            if not (conv.startswith(("REAL_TO_", "LREAL_TO_")) or conv in ("ROUND", "TRUNC")):
                continue
            if not isinstance(ctx.type_of(inner), t.IntType):
                continue
            position = _is_position(inner_info.inputs[0][1])
            if position is not None:
                yield ctx.finding("SA302", f"{text_of(inner_info.inputs[0][1])} looks like a position ('{position}') "
                                           f"and is converted to an integer before formatting: it loses its "
                                           f"decimals", call.span)


def _receives(ctx: PouContext) -> dict[str, dict]:
    """Receive buffers: array key → {'size': key or None, 'size_text', 'rcvsize': key or None,
    'line', 'instance'} from the calls of SktTCPRcv/SktUDPRcv instances."""
    out: dict[str, dict] = {}
    for node in ctx.cfg.nodes:
        for call in node_calls(node):
            info = ctx.facts.call(call)
            if info is None or not info.is_fb:
                continue
            pins = _RECEIVE_FBS.get(info.pou.name.upper())
            if pins is None:
                continue
            args = {var.key: value for var, value in info.inputs}
            data = args.get(pins[0])
            if data is None:
                continue
            array = place_key(root_expr(data) if isinstance(data, n.Index) else data, ctx.facts)
            if isinstance(data, n.Index):
                array = place_key(data.base, ctx.facts)
            if array is None:
                continue
            size = args.get(pins[1])
            received = next((target for var, target, _ in info.outputs if var.key == pins[2]), None)
            out[array] = {"size": place_key(size, ctx.facts) if size is not None else None,
                          "size_text": text_of(size) if size is not None else None,
                          "rcvsize": place_key(received, ctx.facts) if received is not None else None,
                          "rcvsize_text": text_of(received) if received is not None else None,
                          "line": call.span.line, "instance": text_of(info.instance)}
    return out


@rule("SA303", "fixed-receive-size",
      "a receive buffer is read with a fixed size instead of the received length",
      """
      SktTCPRcv writes `RcvSize` bytes into its buffer and leaves the rest as it was. Reading the
      buffer with the requested `Size` (or any constant) instead of `RcvSize` picks up the tail of
      an older, longer message: stale bytes that FIND and parsers then match. Use the length the
      receive reported.
      """,
      """
      FUNCTION_BLOCK Rx
      VAR_OUTPUT text : STRING[256]; END_VAR
      VAR rcv : SktTCPRcv; sock : _sSOCKET; buf : ARRAY[0..255] OF BYTE; received : UINT; END_VAR
      rcv(Execute := TRUE, Socket := sock, Size := 256, RcvDat := buf[0], RcvSize => received);
      IF rcv.Done THEN
          text := AryToString(buf[0], 256);
      END_IF;
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Rx
      VAR_OUTPUT text : STRING[256]; END_VAR
      VAR rcv : SktTCPRcv; sock : _sSOCKET; buf : ARRAY[0..255] OF BYTE; received : UINT; END_VAR
      rcv(Execute := TRUE, Socket := sock, Size := 256, RcvDat := buf[0], RcvSize => received);
      IF rcv.Done THEN
          text := AryToString(buf[0], received);
      END_IF;
      END_FUNCTION_BLOCK
      """,
      thesis="`AryToString(TCP_Rcv_Data[0],TCP_Rcv_Size)` in the command FBs; CBT_Connect uses RcvSize "
             "(st_src/README.md 8.3, sysmac.md 8.3; CBT_MoveAbsolute.st:529, 591).")
def fixed_receive_size(ctx: PouContext):
    receives = _receives(ctx)
    if not receives:
        return
    for node, state, call, info in _calls(ctx):
        if info.is_fb or info.pou.name.upper() != "ARYTOSTRING" or len(info.inputs) < 2:
            continue
        data, count = info.inputs[0][1], info.inputs[1][1]
        array = place_key(data.base if isinstance(data, n.Index) else data, ctx.facts)
        rcv = receives.get(array or "")
        if rcv is None:
            continue
        count_key = place_key(count, ctx.facts)
        if count_key is not None and count_key == rcv["rcvsize"]:
            continue
        rng = ctx.value(count, state)
        is_size = count_key is not None and count_key == rcv["size"]
        if not is_size and not is_point(rng):
            continue
        what = f"{text_of(count)} = {fmt(rng)}" if rng is not None else text_of(count)
        origin = f"the size requested from {rcv['instance']} (line {rcv['line']})" if is_size \
            else "a fixed size"
        instead = f"the {rcv['rcvsize_text']} it received" if rcv["rcvsize_text"] else "its RcvSize output"
        yield ctx.finding("SA303", f"{text_of(call)} reads {what} bytes, {origin}, not {instead}: "
                                   f"bytes past the reply are stale data of an earlier message", call.span)


def _concat_length(call: n.Expr, ctx: PouContext, state) -> tuple[int, int] | None:
    """The unclipped length range of a (nested) CONCAT."""
    info = ctx.facts.call(call) if isinstance(call, n.Call) else None
    if info is None or info.is_fb or info.pou.name.upper() != "CONCAT":
        return ctx.value(call, state)
    total = (0, 0)
    for arg in [value for _, value in info.inputs] + list(info.extra):
        piece = _concat_length(arg, ctx, state) or (0, MAX_STRING_BYTES)
        total = (total[0] + piece[0], total[1] + piece[1])
    return total


@rule("SA304", "concat-overflow",
      "a string built by CONCAT can be longer than the STRING[n] it is stored in",
      """
      A STRING[n] holds n-1 bytes; a longer value is cut at assignment (sysmac.md 3,
      `string_overflow`), and CONCAT itself fails beyond 1985 bytes. For a frame that is then
      sent, a cut means a frame without its end (or its checksum computed over different bytes).
      The bound comes from the operands: literals, the declared sizes of variables and what the
      program assigns to them (e.g. the longest text RealToFormatString can return).
      """,
      """
      FUNCTION_BLOCK Cmd
      VAR_INPUT name, args : STRING[100]; END_VAR
      VAR_OUTPUT frame : STRING[64]; END_VAR
      frame := CONCAT(name, '(', args, ')');      (* up to 202 bytes into 63 *)
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Cmd
      VAR_INPUT name, args : STRING[100]; END_VAR
      VAR_OUTPUT frame : STRING[256]; END_VAR
      frame := CONCAT(name, '(', args, ')');
      END_FUNCTION_BLOCK
      """)
def concat_overflow(ctx: PouContext):
    for node, state in ctx.reachable_nodes():
        if node.kind != "assign":
            continue
        value = node.stmt.value
        info = ctx.facts.call(value) if isinstance(value, n.Call) else None
        target = ctx.type_of(node.stmt.target)
        if info is None or info.pou.name.upper() != "CONCAT" or not isinstance(target, t.StringType):
            continue
        length = _concat_length(value, ctx, state)
        if length is None:
            continue
        limit = min(target.max_bytes, MAX_STRING_BYTES)
        if length[1] <= limit:
            continue
        where = f"the {target.max_bytes} bytes of {target.name} {text_of(node.stmt.target)}"
        yield ctx.finding("SA304", f"this CONCAT can be up to {length[1]} bytes long, more than {where}: "
                                   f"the text is cut", value.span)
