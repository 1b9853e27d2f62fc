"""SA5xx: resources a step sequence holds across scans — sockets and flags."""

from __future__ import annotations

from stvm.lint.context import PouContext
from stvm.lint.facts_view import node_calls, place_key, text_of
from stvm.lint.machines import Resource, positive_members, leaks, nonlocal_flags, step_machines
from stvm.lint.findings import rule


def _fb_calls(ctx: PouContext, fb_name: str):
    """(instance key, instance text, Execute place key or None, call) of calls of FB type fb_name."""
    for node in ctx.cfg.nodes:
        for call in node_calls(node):
            info = ctx.facts.call(call)
            if info is None or not info.is_fb or info.pou.name.upper() != fb_name or info.instance is None:
                continue
            execute = next((value for var, value in info.inputs if var.key == "execute"), None)
            yield (place_key(info.instance, ctx.facts), text_of(info.instance),
                   place_key(execute, ctx.facts) if execute is not None else None, call)


def _assigns_true(ctx: PouContext, key: str | None):
    if key is None:
        return set()
    out = set()
    for node, state in ctx.reachable_nodes():
        if node.kind == "assign" and place_key(node.stmt.target, ctx.facts) == key \
                and ctx.value(node.stmt.value, state) == (1, 1):
            out.add(node.index)
    return out


def _condition_edges(ctx: PouContext, member_key: str) -> set[int]:
    out = set()
    for node in ctx.cfg.nodes:
        for edge in node.succs:
            if edge.label and edge.label[0] == "true" and member_key in positive_members(edge.label[1], ctx):
                out.add(id(edge))
    return out


def _steps(states) -> str:
    values = sorted(states)
    if not values:
        return ""
    shown = ", ".join(str(v) for v in values[:6]) + (", …" if len(values) > 6 else "")
    return f" (step {shown})" if len(values) == 1 else f" (steps {shown})"


@rule("SA501", "socket-leak",
      "a socket opened with SktTCPConnect is not closed on a path that ends the sequence with an error",
      """
      A TCP socket is a controller resource (an NJ has 16 TCP sockets; the 17th connect fails)
      and the peer keeps its side open too. When an error ends the step sequence after the
      connection is up (or while a connect is still pending), the socket must be closed on that
      path — by the error path itself, or by moving to a closing step that runs. Otherwise the
      handle leaks, and the next Execute overwrites it with a new connection.
      """,
      """
      FUNCTION_BLOCK Link
      VAR_INPUT start, failed, stop : BOOL; END_VAR
      VAR_OUTPUT Error : BOOL; END_VAR
      VAR step : INT; connect : SktTCPConnect; close : SktClose; sock : _sSOCKET;
          connectExe, closeExe : BOOL; END_VAR
      CASE step OF
          0: IF start THEN connectExe := TRUE; step := 10; END_IF;
          10: IF connect.Done THEN connectExe := FALSE; step := 20; END_IF;
          20: IF failed THEN
                  Error := TRUE;          (* the socket stays open *)
              ELSIF stop THEN
                  step := 30;
              END_IF;
          30: closeExe := TRUE;
      END_CASE;
      connect(Execute := connectExe, SrcTcpPort := 0, DstAdr := '10.0.0.1', DstTcpPort := 5890, Socket => sock);
      close(Execute := closeExe, Socket := sock);
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Link
      VAR_INPUT start, failed, stop : BOOL; END_VAR
      VAR_OUTPUT Error : BOOL; END_VAR
      VAR step : INT; connect : SktTCPConnect; close : SktClose; sock : _sSOCKET;
          connectExe, closeExe : BOOL; END_VAR
      CASE step OF
          0: IF start THEN connectExe := TRUE; step := 10; END_IF;
          10: IF connect.Done THEN connectExe := FALSE; step := 20; END_IF;
          20: IF failed THEN
                  Error := TRUE;
                  step := 30;             (* close, then report *)
              ELSIF stop THEN
                  step := 30;
              END_IF;
          30: closeExe := TRUE;
      END_CASE;
      connect(Execute := connectExe, SrcTcpPort := 0, DstAdr := '10.0.0.1', DstTcpPort := 5890, Socket => sock);
      close(Execute := closeExe, Socket := sock);
      END_FUNCTION_BLOCK
      """,
      thesis="CBT_Connect closes (step 100) only while Busy: after an error end (16#21 timeout, 16#90 "
             "connection lost, …) the socket stays open (st_src/README.md 8.11, sysmac.md 8.11).")
def socket_leak(ctx: PouContext):
    connects = list(_fb_calls(ctx, "SKTTCPCONNECT"))
    if not connects:
        return
    closes = list(_fb_calls(ctx, "SKTCLOSE"))
    machines = step_machines(ctx)
    for inst_key, inst_text, execute, call in connects:
        if inst_key is None:
            continue
        release_nodes = set()
        close_text = ""
        for _k, text, close_exe, _c in closes:
            release_nodes |= _assigns_true(ctx, close_exe)
            close_text = text
        resource = Resource(inst_text, frozenset(_assigns_true(ctx, execute)), frozenset(release_nodes),
                            frozenset(_condition_edges(ctx, f"{inst_key}.done")),
                            frozenset(_condition_edges(ctx, f"{inst_key}.error")), call.span.line)
        for machine in machines:
            for leak in leaks(ctx, machine, [resource], machines).get(0, []):
                closing = f" without running {close_text}" if close_text else " and nothing closes it"
                yield ctx.finding("SA501", f"this error ends the sequence{_steps(leak.states)} with the socket of "
                                           f"{inst_text} (line {call.span.line}) still open{closing}", leak.span)


@rule("SA502", "flag-not-cleared",
      "a flag set on entering a step is not cleared on every path that ends the sequence",
      """
      Step sequences often raise a flag others can see — an output, a member of a shared in-out
      struct ("robot busy", "waiting for reply"), a global — when they enter a step, and clear it
      when they leave. An error path that ends the sequence without clearing it leaves the flag
      set for ever: other blocks wait on it, or refuse to start. Only flags visible outside the
      block are checked; locals are reset at the next start anyway.
      """,
      """
      FUNCTION_BLOCK Cmd
      VAR_OUTPUT Error : BOOL; END_VAR
      VAR_IN_OUT Link : BOOL; END_VAR      (* TRUE: a reply is pending *)
      VAR_INPUT sent, lost, replied : BOOL; END_VAR
      VAR step : INT; END_VAR
      CASE step OF
          0: IF sent THEN Link := TRUE; step := 10; END_IF;
          10: IF replied THEN Link := FALSE; step := 0;
              ELSIF lost THEN
                  Error := TRUE;          (* Link stays TRUE *)
              END_IF;
      END_CASE;
      END_FUNCTION_BLOCK
      """,
      """
      FUNCTION_BLOCK Cmd
      VAR_OUTPUT Error : BOOL; END_VAR
      VAR_IN_OUT Link : BOOL; END_VAR
      VAR_INPUT sent, lost, replied : BOOL; END_VAR
      VAR step : INT; END_VAR
      CASE step OF
          0: IF sent THEN Link := TRUE; step := 10; END_IF;
          10: IF replied THEN Link := FALSE; step := 0;
              ELSIF lost THEN
                  Link := FALSE;
                  Error := TRUE;
              END_IF;
      END_CASE;
      END_FUNCTION_BLOCK
      """,
      thesis="`CBT.WaitingReturn` stays TRUE when a move FB fails after sending (receive error, lost "
             "connection: 16#70, 16#90, 16#99, 16#100), so every later FB fails with 16#11 "
             "(tests/thesis/FIDELITY_FINDINGS.md, 'Connection lost paths'; sysmac.md 8.2).")
def flag_not_cleared(ctx: PouContext):
    machines = step_machines(ctx)
    for machine in machines:
        resources, texts, first_sets = [], [], []
        for key, nodes in nonlocal_flags(ctx, machine).items():
            acquire, release = set(), set()
            first_set = None
            for node in nodes:
                state = ctx.state_at(node)
                if state is None:
                    continue
                if ctx.value(node.stmt.value, state) == (1, 1):
                    acquire.add(node.index)
                    if node.index in machine.inside and (first_set is None or node.stmt.span.line < first_set.line):
                        first_set = node.stmt.span
                else:
                    release.add(node.index)
            if not release:
                continue   # never cleared by this POU: a latch by design, not a held flag
            text = text_of(nodes[0].stmt.target)
            resources.append(Resource(text, frozenset(acquire), frozenset(release),
                                      acquire_line=first_set.line if first_set else 0))
            texts.append(text)
            first_sets.append(first_set)
        for index, found in leaks(ctx, machine, resources, machines).items():
            text, first_set = texts[index], first_sets[index]
            for leak in found:
                where = f", set TRUE at line {first_set.line}," if first_set else ""
                yield ctx.finding("SA502", f"{text}{where} is still TRUE when this path ends the "
                                           f"sequence{_steps(leak.states)}: nothing clears it afterwards",
                                  leak.span)
