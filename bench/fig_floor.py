"""Issue 33 items 2 and 4, the floor: the generated code of thesis FB scans against the same ST
written by hand in plain Python.

The question it answers: how much of the ST programs' share of a scan is the lowering's, and how
much is the ST as written (a CASE on a status, an edge detector, the socket struct copied into
three or six socket FBs every call), which even a careful hand translation must execute?

Each case runs on the live instances of the PnP golden scenario (st_src/scenarios/
golden_pnp_cycle.toml) stopped at scan 200, where the connection is up and the thesis sits in its
steady state for the rest of the run (CBT_Connect at FB_Status 2, FB_Step 90; the command FBs idle):

* `idle command FB`: one call of Program_Example's CBT_ChangeBase instance (Execute FALSE): the
  body, its three socket FBs' input copies and their (skipped: quiet) native calls;
* `CBT_Connect connected`: one call of Program_Example's CBT_Connect instance at step 90: its
  body, six socket FBs, two TONs (the stdlib's natives: the same objects in both versions);
* `CBT_Connect idle`: the same on a fresh instance with Execute FALSE.

The hand-written versions (`changebase_hand`, `connect_hand` below) read and write the very same
instance objects (the generated classes' attributes), so both versions start from one state and
end in one state. They are what a careful Python programmer writes for the same ST: locals for
values read twice, the R_TRIG/F_TRIG inlined with its result kept in a local, the socket
struct's five leaves read once and stored into each socket FB, stores that cannot change anything
(`FB_Status := 0` in state 0) left out; every ST-visible store the ST makes is kept (the FBs'
inputs hold the copied values after the call, as the trace, the HMI, OPC UA and the debugger
expect). They use what the programmer knows: a socket FB's native touches only its own instance,
so the connection's socket struct is the same before and after each socket FB call (the
lowering's `share_struct_sources` proves the same for a run of such calls). They implement the CASE steps the timed and checked scans take; any other
step raises, so the equivalence check below cannot pass by accident.

Before timing, each case checks equivalence: two deep copies of the instance (and everything it
reaches: the connection struct, the natives' state) run the generated and the hand version side by
side over a sequence of calls that leaves the steady state (Execute rising with the robot
disconnected for the command FB: status 0-1-2-3-4, step 10; the 1 s timer ending for CBT_Connect:
step 90-80-90 with the socket status query) and every variable must match after every call.

Rows: the generated call and the hand-written call in CPU µs per call (each the median of
alternating rounds), the ratio generated / hand, and each against the FOR-100 yardstick; then the
ST programs' CPU per scan over the golden run (both programs, generated code and the natives they
call), and that divided by the cases' median ratio: an estimate of the same scan written by hand.
Run alone: `python -m bench --only floor`, or `python bench/fig_floor.py` (`--opcodes`: bytecodes
and Python calls per call of both versions, exact).
"""

from __future__ import annotations

import copy
import statistics
import sys
import time
from pathlib import Path

if __name__ == "__main__":      # run as a script: the repository root makes `bench` importable
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.registry import ROOT, Row, figure, for_loop_us  # noqa: E402

SCENARIO = ROOT / "st_src" / "scenarios" / "golden_pnp_cycle.toml"
FILES = [ROOT / "st_src" / "PnP_Example.st"]
STEADY_SCAN = 200       # connected from scan ~40 on; CBT_Connect stays at step 90 for the run
SECOND_NS = 1_000_000_000


# ---------------------------------------------------------------- the hand-written versions

def changebase_hand(fb, ctx, array_ref) -> None:
    """CBT_ChangeBase (st_src/CBT_ChangeBase.st) by hand: every statement of its body with the
    steps 0 and 10 of its step CASE (the idle scan and the checked scans take no other)."""
    execute = fb.v_execute
    cbt = fb.v_cbt
    trig = fb.v_r_trig_execute          # R_TRIG(CLK := Execute, Q => FlagExecute)
    rising = execute and not trig.v_m
    trig.v_clk = execute
    trig.v_q = rising
    trig.v_m = execute
    fb.v_flagexecute = rising
    if rising and fb.v_fb_status != 2:
        fb.v_iparameters._assign(fb.v_parameters)
        fb.v_fb_status = 1
        fb.v_fb_step = 10
    if execute and not cbt.v_connected:
        fb.v_toerror_sts = True
        fb.v_toerrorid = 153
        fb.v_toerrordescrip = b'Robot not connected'
    status = fb.v_fb_status
    if status == 0:
        pass            # FB_Status := 0 stores what it holds
    elif status == 1:
        fb.v_toerror_sts = False
        fb.v_todone_sts = False
        fb.v_done = False
        fb.v_busy = False
        fb.v_error = False
        fb.v_errorid = 0
        fb.v_errordescrip = b''
        fb.v_fb_status = 2
    elif status == 2:
        fb.v_done = False
        fb.v_busy = True
        fb.v_error = False
        fb.v_errorid = 0
        fb.v_errordescrip = b''
        if fb.v_toerror_sts:
            fb.v_fb_status = 3
        if fb.v_todone_sts:
            fb.v_fb_status = 5
    elif status == 3:
        fb.v_done = False
        fb.v_busy = False
        fb.v_error = True
        fb.v_errorid = fb.v_toerrorid
        fb.v_errordescrip = fb.v_toerrordescrip
        if not execute:
            fb.v_fb_status = 4
    elif status == 4:
        fb.v_done = False
        fb.v_busy = False
        fb.v_error = False
        fb.v_errorid = fb.v_toerrorid
        fb.v_errordescrip = fb.v_toerrordescrip
    elif status == 5:
        fb.v_done = True
        fb.v_busy = False
        fb.v_error = False
        fb.v_errorid = 0
        fb.v_errordescrip = b''
        if not execute:
            fb.v_fb_status = 6
    elif status == 6:
        fb.v_done = False
        fb.v_busy = False
        fb.v_error = False
        fb.v_errorid = 0
        fb.v_errordescrip = b''
    if fb.v_busy:
        step = fb.v_fb_step
        if step == 10:
            fb.v_tcp_clear_buffer_exe = False
            fb.v_tcp_send_exe = False
            fb.v_tcp_rcv_exe = False
            fb.v_toerrorid = 0
            fb.v_toerrordescrip = b''
            if cbt.v_connected and not cbt.v_waitingreturn:
                fb.v_fb_step = 20
            else:
                fb.v_toerror_sts = True
                fb.v_toerrorid = 16
                fb.v_toerrordescrip = b'Robot not connected'
        elif step != 0:
            raise NotImplementedError(f"CBT_ChangeBase step {step} is not written by hand")
    # the three socket FBs: Socket := CBT.Socket copied in, the native called unless quiet
    sock = cbt.v_socket
    handle = sock.v_handle
    src, dst = sock.v_srcadr, sock.v_dstadr
    src_port, src_ip, dst_port, dst_ip = src.v_portno, src.v_ipadr, dst.v_portno, dst.v_ipadr
    clear = fb.v_tcp_clear_buffer
    clear.v_execute = execute_pin = fb.v_tcp_clear_buffer_exe
    s = clear.v_socket
    s.v_handle = handle
    a = s.v_srcadr
    a.v_portno = src_port
    a.v_ipadr = src_ip
    a = s.v_dstadr
    a.v_portno = dst_port
    a.v_ipadr = dst_ip
    if execute_pin is not clear._impl.quiet:
        clear._impl.call(clear, ctx)
    send = fb.v_tcp_send
    send.v_execute = execute_pin = fb.v_tcp_send_exe
    s = send.v_socket
    s.v_handle = handle
    a = s.v_srcadr
    a.v_portno = src_port
    a.v_ipadr = src_ip
    a = s.v_dstadr
    a.v_portno = dst_port
    a.v_ipadr = dst_ip
    data = fb.v_tcp_send_data
    bound = send.v_senddat              # SendDat := TCP_Send_Data (an in-out: bound at each call)
    if bound is None or bound.data is not data or bound.start:
        send.v_senddat = array_ref(data, 0)
    send.v_size = fb.v_tcp_send_size
    if execute_pin is not send._impl.quiet:
        send._impl.call(send, ctx)
    rcv = fb.v_tcp_rcv
    rcv.v_execute = execute_pin = fb.v_tcp_rcv_exe
    s = rcv.v_socket
    s.v_handle = handle
    a = s.v_srcadr
    a.v_portno = src_port
    a.v_ipadr = src_ip
    a = s.v_dstadr
    a.v_portno = dst_port
    a.v_ipadr = dst_ip
    rcv.v_timeout = fb.v_tcp_rcv_timeout
    rcv.v_size = fb.v_tcp_rcv_size
    data = fb.v_tcp_rcv_data
    bound = rcv.v_rcvdat
    if bound is None or bound.data is not data or bound.start:
        rcv.v_rcvdat = array_ref(data, 0)
    if execute_pin is not rcv._impl.quiet:
        rcv._impl.call(rcv, ctx)
    fb.v_tcp_rcv_rcvsize = rcv.v_rcvsize


def _socket_in(target, handle, src_port, src_ip, dst_port, dst_ip) -> None:
    """A socket struct's five leaves stored into `target` (CBT_Connect's `Socket => CBT.Socket`,
    once a call; the five socket FB inputs after it are written inline)."""
    target.v_handle = handle
    a = target.v_srcadr
    a.v_portno = src_port
    a.v_ipadr = src_ip
    a = target.v_dstadr
    a.v_portno = dst_port
    a.v_ipadr = dst_ip


def connect_hand(fb, ctx, array_ref, get_time) -> None:
    """CBT_Connect (st_src/CBT_Connect.st) by hand: every statement of its body with the steps 80
    and 90 of its step CASE (the connected scans), and none of the others (idle: not busy).

    Its status CASE repeats `changebase_hand`'s line for line on purpose: every thesis FB carries
    its own copy of that CASE in ST, and a Python function shared by the two would add a call the
    ST does not make (the figure compares like with like)."""
    execute = fb.v_execute
    cbt = fb.v_cbt
    trig = fb.v_r_trig_execute          # R_TRIG(CLK := Execute, Q => FlagExecute)
    rising = execute and not trig.v_m
    trig.v_clk = execute
    trig.v_q = rising
    trig.v_m = execute
    fb.v_flagexecute = rising
    if rising and fb.v_fb_status != 2:
        fb.v_fb_status = 1
        fb.v_fb_step = 10
        fb.v_local_portip = 0
        fb.v_addressip = fb.v_ipaddress
        fb.v_dest_portip = fb.v_ipport
        fb.v_connectiontimeout = fb.v_time_out
    trig = fb.v_f_trig_execute          # F_TRIG(CLK := Execute, Q => FalseExecute)
    falling = not execute and trig.v_m
    trig.v_clk = execute
    trig.v_q = falling
    trig.v_m = execute
    fb.v_falseexecute = falling
    if falling:
        fb.v_fb_step = 100
    status = fb.v_fb_status
    if status == 0:
        pass            # FB_Status := 0 stores what it holds
    elif status == 1:
        fb.v_toerror_sts = False
        fb.v_todone_sts = False
        fb.v_done = False
        fb.v_busy = False
        fb.v_error = False
        fb.v_errorid = 0
        fb.v_errordescrip = b''
        fb.v_fb_status = 2
    elif status == 2:
        fb.v_done = False
        fb.v_busy = True
        fb.v_error = False
        fb.v_errorid = 0
        fb.v_errordescrip = b''
        if fb.v_toerror_sts:
            fb.v_fb_status = 3
        if fb.v_todone_sts:
            fb.v_fb_status = 5
    elif status == 3:
        fb.v_done = False
        fb.v_busy = False
        fb.v_error = True
        fb.v_errorid = fb.v_toerrorid
        fb.v_errordescrip = fb.v_toerrordescrip
        if not execute:
            fb.v_fb_status = 4
    elif status == 4:
        fb.v_done = False
        fb.v_busy = False
        fb.v_error = False
        fb.v_errorid = fb.v_toerrorid
        fb.v_errordescrip = fb.v_toerrordescrip
    elif status == 5:
        fb.v_done = True
        fb.v_busy = False
        fb.v_error = False
        fb.v_errorid = 0
        fb.v_errordescrip = b''
        if not execute:
            fb.v_fb_status = 6
    elif status == 6:
        fb.v_done = False
        fb.v_busy = False
        fb.v_error = False
        fb.v_errorid = 0
        fb.v_errordescrip = b''
    if fb.v_busy:
        step = fb.v_fb_step
        if step == 90:
            if not fb.v_firstconnection:
                fb.v_lastconntime = get_time(ctx)
                fb.v_firstconnection = True
            fb.v_timer_1_enable = True
            if fb.v_timer_1_done:
                fb.v_timer_1_enable = False
                fb.v_fb_step = ((step - 10 + 32768) & 65535) - 32768
            if fb.v_socketstatus == 5:
                raise NotImplementedError("CBT_Connect: socket lost is not written by hand")
        elif step == 80:
            fb.v_get_tcp_status_exe = True
            status_fb = fb.v_get_tcp_status
            if status_fb.v_done:
                cbt.v_connected = True
                fb.v_connected = True
                fb.v_get_tcp_status_exe = False
                fb.v_fb_step = 90
            if status_fb.v_error:
                fb.v_toerrorid = 128
                fb.v_toerrordescrip = b'Get TCP Status Error'
                fb.v_get_tcp_status_exe = False
                fb.v_toerror_sts = True
        elif step != 0:
            raise NotImplementedError(f"CBT_Connect step {step} is not written by hand")
    # SktTCPConnect: its Socket output copied to CBT.Socket after the call
    connect = fb.v_tcp_connect
    connect.v_execute = execute_pin = fb.v_tcp_connect_exe
    connect.v_srctcpport = fb.v_local_portip
    connect.v_dstadr = fb.v_addressip
    connect.v_dsttcpport = fb.v_dest_portip
    if execute_pin is not connect._impl.quiet:
        connect._impl.call(connect, ctx)
    out = connect.v_socket
    sock = cbt.v_socket
    a, b = out.v_srcadr, out.v_dstadr
    handle, src_port, src_ip, dst_port, dst_ip = out.v_handle, a.v_portno, a.v_ipadr, b.v_portno, b.v_ipadr
    _socket_in(sock, handle, src_port, src_ip, dst_port, dst_ip)
    # five socket FBs: Socket := CBT.Socket (the values just stored) copied in
    clear = fb.v_tcp_clear_buffer
    clear.v_execute = execute_pin = fb.v_tcp_clear_buffer_exe
    s = clear.v_socket
    s.v_handle = handle
    a = s.v_srcadr
    a.v_portno = src_port
    a.v_ipadr = src_ip
    a = s.v_dstadr
    a.v_portno = dst_port
    a.v_ipadr = dst_ip
    if execute_pin is not clear._impl.quiet:
        clear._impl.call(clear, ctx)
    status_fb = fb.v_get_tcp_status
    status_fb.v_execute = execute_pin = fb.v_get_tcp_status_exe
    s = status_fb.v_socket
    s.v_handle = handle
    a = s.v_srcadr
    a.v_portno = src_port
    a.v_ipadr = src_ip
    a = s.v_dstadr
    a.v_portno = dst_port
    a.v_ipadr = dst_ip
    if execute_pin is not status_fb._impl.quiet:
        status_fb._impl.call(status_fb, ctx)
    fb.v_socketstatus = status_fb.v_tcpstatus
    send = fb.v_tcp_send
    send.v_execute = execute_pin = fb.v_tcp_send_exe
    s = send.v_socket
    s.v_handle = handle
    a = s.v_srcadr
    a.v_portno = src_port
    a.v_ipadr = src_ip
    a = s.v_dstadr
    a.v_portno = dst_port
    a.v_ipadr = dst_ip
    data = fb.v_tcp_send_data
    bound = send.v_senddat
    if bound is None or bound.data is not data or bound.start:
        send.v_senddat = array_ref(data, 0)
    send.v_size = fb.v_tcp_send_size
    if execute_pin is not send._impl.quiet:
        send._impl.call(send, ctx)
    rcv = fb.v_tcp_rcv
    rcv.v_execute = execute_pin = fb.v_tcp_rcv_exe
    s = rcv.v_socket
    s.v_handle = handle
    a = s.v_srcadr
    a.v_portno = src_port
    a.v_ipadr = src_ip
    a = s.v_dstadr
    a.v_portno = dst_port
    a.v_ipadr = dst_ip
    rcv.v_timeout = fb.v_tcp_rcv_timeout
    rcv.v_size = fb.v_tcp_rcv_size
    data = fb.v_tcp_rcv_data
    bound = rcv.v_rcvdat
    if bound is None or bound.data is not data or bound.start:
        rcv.v_rcvdat = array_ref(data, 0)
    if execute_pin is not rcv._impl.quiet:
        rcv._impl.call(rcv, ctx)
    fb.v_tcp_rcv_rcvsize = rcv.v_rcvsize
    close = fb.v_tcp_close
    close.v_execute = execute_pin = fb.v_tcp_close_exe
    s = close.v_socket
    s.v_handle = handle
    a = s.v_srcadr
    a.v_portno = src_port
    a.v_ipadr = src_ip
    a = s.v_dstadr
    a.v_portno = dst_port
    a.v_ipadr = dst_ip
    if execute_pin is not close._impl.quiet:
        close._impl.call(close, ctx)
    # the two TONs (the stdlib's native; NanoSecToTime is the identity on TIME, sysmac.md 6)
    timer = fb.v_ton_timeout
    timer.v_in = fb.v_ton_timeout_exe
    timer.v_pt = ((fb.v_connectiontimeout * 100000000 + 2147483648) & 4294967295) - 2147483648
    timer._impl.call(timer, ctx)
    fb.v_timeout = timer.v_q
    timer = fb.v_timer_1
    timer.v_in = fb.v_timer_1_enable
    timer.v_pt = SECOND_NS
    timer._impl.call(timer, ctx)
    fb.v_timer_1_done = timer.v_q


# ---------------------------------------------------------------- state, equivalence, timing

def state_of(obj, seen=None):
    """Every variable reachable from a generated instance, as nested tuples (the natives' state
    too), for comparing two copies."""
    seen = set() if seen is None else seen
    if isinstance(obj, (bool, int, float, bytes, str, type(None))):
        return obj
    if id(obj) in seen:
        return "<seen>"
    seen.add(id(obj))
    if isinstance(obj, list):
        return tuple(state_of(v, seen) for v in obj)
    if isinstance(obj, dict):
        return tuple((k, state_of(v, seen)) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0])))
    names = [n for c in type(obj).__mro__ for n in getattr(c, "__slots__", ())]
    fields = {n: getattr(obj, n) for n in names if hasattr(obj, n)}
    if hasattr(obj, "__dict__"):
        fields.update(vars(obj))
    return (type(obj).__name__,) + tuple((k, state_of(v, seen)) for k, v in sorted(fields.items()))


def check_same(generated, hand, instance, perturb, calls: int, ctx) -> None:
    """Run `generated` and `hand` on two deep copies of `instance` for `calls` calls after
    `perturb(copy)`; every variable must match after every call."""
    saved_now = ctx.now_ns
    try:
        g, h = copy.deepcopy(instance), copy.deepcopy(instance)
        perturb(g, ctx)
        perturb(h, ctx)
        for call in range(calls):
            generated(g)
            hand(h)
            if state_of(g) != state_of(h):
                raise AssertionError(f"hand-written version differs from the generated code after call {call + 1}")
            ctx.now_ns += ctx_step_ns(ctx)
    finally:
        ctx.now_ns = saved_now


def ctx_step_ns(ctx) -> int:
    return 10_000_000      # the scenario's 10 ms scan


def cpu_us(fn, number: int) -> float:
    """Best CPU µs per call of `fn()` over three runs of `number` calls."""
    clock = time.process_time
    best = float("inf")
    for _ in range(3):
        started = clock()
        for _ in range(number):
            fn()
        best = min(best, clock() - started)
    return best / number * 1e6


def bytecodes_per_call(fn, instance) -> tuple[int, int]:
    """(bytecodes, Python calls) of one `fn(instance)`: `sys.settrace` opcode events, exact and
    the same on every run (the view for a loaded machine)."""
    counts = [0, 0]

    def tracer(frame, event, arg):
        frame.f_trace_opcodes = True
        if event == "opcode":
            counts[0] += 1
        elif event == "call":
            counts[1] += 1
        return tracer
    sys.settrace(tracer)
    try:
        fn(instance)
    finally:
        sys.settrace(None)
    return counts[0], counts[1]


def steady_session(scans: int):
    from stvm.project import load
    from stvm.trace import TraceSpec
    from stvm.trace.run import trace_session
    session = trace_session(TraceSpec(FILES, scenario=SCENARIO, watch=[], cycles=scans + 1),
                            load([str(f) for f in FILES]))
    vm = session.vm
    vm.collect_stats = False
    session.wire()
    for _ in range(scans):
        vm.scan()
    return session, vm


def floor_cases(vm):
    """(label, instance, generated call, hand call, perturb for the check, checked calls)."""
    from stvm.runtime.values import ArrayRef
    ctx = vm.ctx
    program = vm.instances["program_example_instance"][1]
    get_time = next(vm.namespace[py] for py, key in vm.project.lowered.natives.items() if key == "GETTIME")
    changebase = program.v_cbt_changebase_instance
    connect = program.v_cbt_connect_instance
    idle_connect = type(connect)()
    idle_connect.v_cbt = copy.deepcopy(connect.v_cbt)

    def call_generated(fb):
        fb()

    def call_changebase(fb):
        changebase_hand(fb, ctx, ArrayRef)

    def call_connect(fb):
        connect_hand(fb, ctx, ArrayRef, get_time)

    def rise_disconnected(fb, _ctx):
        fb.v_execute = True
        fb.v_cbt.v_connected = False

    def timer_ends(fb, ctx):
        ctx.now_ns += 2 * SECOND_NS    # timer_1 (1 s) ends: step 90 -> 80 -> status query -> 90

    def unchanged(fb, _ctx):
        pass

    checks = {"changebase": [(rise_disconnected, 6), (unchanged, 3)],
              "connect": [(timer_ends, 12), (unchanged, 3)],
              "idle connect": [(unchanged, 3)]}
    return [("idle command FB (CBT_ChangeBase, Execute FALSE)", changebase, call_generated, call_changebase,
             checks["changebase"]),
            ("CBT_Connect connected (status 2, step 90)", connect, call_generated, call_connect, checks["connect"]),
            ("CBT_Connect idle (Execute FALSE, fresh)", idle_connect, call_generated, call_connect,
             checks["idle connect"])]


def st_part_us(scans: int) -> float:
    """CPU µs per scan of the two ST programs (generated code and the natives they call) over the
    first `scans` scans of the golden run: each program call timed as the VM's scan loop makes it
    (the schedule's callables wrapped; the wrapper's own clock reads are measured and subtracted)."""
    from stvm.project import load
    from stvm.trace import TraceSpec
    from stvm.trace.run import trace_session
    session = trace_session(TraceSpec(FILES, scenario=SCENARIO, watch=[], cycles=scans),
                            load([str(f) for f in FILES]))
    vm = session.vm
    vm.collect_stats = False
    session.wire()
    clock = time.process_time_ns
    spent = [0]

    def timed(program):
        def run():
            started = clock()
            program()
            spent[0] += clock() - started
        return run
    calls = 0
    for tasks in vm._schedule:          # the VM's per-tick program lists (bench only: wrapped in place)
        for _, programs in tasks:
            calls += len(programs)
            programs[:] = [timed(p) for p in programs]
    try:
        for _ in range(scans):
            vm.scan()
    finally:
        session.close()
    empty = 0                           # what the wrapper costs around a program that does nothing
    for _ in range(scans * calls):
        started = clock()
        spent_none = clock() - started
        empty += spent_none
    return max(spent[0] - empty, 0) / scans / 1e3


def measure(smoke: bool) -> list[tuple[str, float, float, list[float]]]:
    """[(case, generated µs, hand µs, ratios)] after the equivalence checks."""
    session, vm = steady_session(60 if smoke else STEADY_SCAN)
    try:
        results = []
        for label, instance, generated, hand, checks in floor_cases(vm):
            for perturb, calls in checks:
                check_same(generated, hand, instance, perturb, calls, vm.ctx)
            generated(instance)         # a fresh instance's first call sets its inputs
            before = state_of(instance)
            number = 200 if smoke else 20000
            rounds = 1 if smoke else 7
            gen_us, hand_us, ratios = [], [], []
            for _ in range(rounds):     # alternating: both see the same minutes of the machine
                g = cpu_us(lambda: generated(instance), number)
                h = cpu_us(lambda: hand(instance), number)
                gen_us.append(g)
                hand_us.append(h)
                ratios.append(g / h)
            if state_of(instance) != before:
                raise AssertionError(f"{label}: the timed state is not a fixed point of the call")
            results.append((label, statistics.median(gen_us), statistics.median(hand_us), ratios))
        return results
    finally:
        session.close()


@figure("floor: generated vs hand-written", item="issue 33 items 2, 4", tags=("trace", "scale"))
def floor_figure(smoke: bool) -> list[Row]:
    yard = for_loop_us(rounds=3 if smoke else 5)
    rows = []
    ratios_all: list[float] = []
    for label, gen_us, hand_us, ratios in measure(smoke):
        spread = f"{min(ratios):.2f}-{max(ratios):.2f}"
        rows.append(Row(f"{label}: generated / hand-written", gen_us, "us", "hand-written", hand_us, "us", "",
                        ratio=statistics.median(ratios),
                        note=f"median of {len(ratios)} alternating rounds ({spread})"))
        rows.append(Row(f"  {label}: hand-written", hand_us, "us", "FOR-100", yard, "us", "",
                        note="the ST as written, by hand, in plain Python"))
        ratios_all.extend(ratios)
    scans = 300 if smoke else 9200
    st_us = st_part_us(scans)
    rows.append(Row("ST programs of a golden scan (generated code + natives)", st_us, "us", "FOR-100", yard, "us",
                    "", note=f"mean over the {scans} scans of the golden run"))
    factor = statistics.median(ratios_all)
    rows.append(Row("  the same written by hand (estimate: / the cases' median ratio)", st_us / factor, "us",
                    "FOR-100", yard, "us", "", note=f"generated / hand-written = {factor:.2f} in the cases above"))
    return rows


if __name__ == "__main__":
    import argparse
    ap = argparse.ArgumentParser(description="generated code vs hand-written Python, thesis FB scans")
    ap.add_argument("--smoke", action="store_true")
    ap.add_argument("--opcodes", action="store_true", help="bytecodes and Python calls per call instead of CPU")
    args = ap.parse_args()
    if args.opcodes:
        session, vm = steady_session(STEADY_SCAN)
        for label, instance, generated, hand, _ in floor_cases(vm):
            generated(instance)
            (gen_ops, gen_calls), (hand_ops, hand_calls) = (bytecodes_per_call(f, instance) for f in (generated, hand))
            print(f"{label}: generated {gen_ops} bytecodes, {gen_calls} calls; hand {hand_ops} bytecodes, "
                  f"{hand_calls} calls; ratio {gen_ops / hand_ops:.2f}")
        session.close()
        raise SystemExit(0)
    yard = for_loop_us()
    print(f"FOR-100 yardstick {yard:.2f} us")
    for label, gen_us, hand_us, ratios in measure(args.smoke):
        print(f"{label}: generated {gen_us:.2f} us, hand {hand_us:.2f} us, ratio {statistics.median(ratios):.2f} "
              f"({min(ratios):.2f}-{max(ratios):.2f}); hand = {hand_us / yard:.2f} FOR-100, "
              f"generated = {gen_us / yard:.2f} FOR-100")
    st_us = st_part_us(300 if args.smoke else 9200)
    print(f"ST programs per golden scan (generated + natives): {st_us:.2f} us = {st_us / yard:.2f} FOR-100")
