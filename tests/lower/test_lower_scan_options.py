"""The scan-time optimisations of issue 16 (stvm/lower/options.py): each switchable, each changing
only the generated code, never what the program computes.

Each test lowers a small program with the option on and off, checks the generated code shows the
optimisation only when on, and runs both for several scans with the same inputs: every variable
must end up the same. The last test runs thesis golden traces with all of them off.
"""

from __future__ import annotations

import contextlib
import functools
import re
import sys
from pathlib import Path

import pytest

import stvm.lower
from core_helpers import load_st
from stvm.lower import codegen
from stvm.lower.options import DEFAULT_OPTIONS, LowerOptions

SCAN_OPTIONS = ("hot_path_cache", "inline_input_copy", "direct_native_calls", "skip_quiet_native_calls",
                "reuse_array_refs", "inline_small_fbs", "share_struct_sources")


@contextlib.contextmanager
def lowering(options: LowerOptions):
    """Projects loaded inside are lowered with `options` (load_st never uses the cache)."""
    original = stvm.lower.lower_project
    stvm.lower.lower_project = functools.partial(codegen.lower_project, options=options)
    try:
        yield
    finally:
        stvm.lower.lower_project = original


def load_with(source: str, options: LowerOptions):
    with lowering(options):
        return load_st(source)


def run_both(source: str, option: str, scans: int, inputs, paths):
    """(code on, code off, values on, values off): `inputs(scan)` gives {path: value} per scan."""
    results = []
    for options in (DEFAULT_OPTIONS, DEFAULT_OPTIONS.without(option)):
        project = load_with(source, options)
        vm = project.start(scan="10ms")
        seen = []
        for scan in range(scans):
            for path, value in inputs(scan).items():
                vm[path] = value
            vm.scan()
            seen.append({p: vm[p] for p in paths})
        results.append((project.lowered.source, seen))
    (on_code, on_seen), (off_code, off_seen) = results
    assert on_seen == off_seen
    return on_code, off_code, on_seen


def test_options_are_named_switches_on_by_default():
    for name in SCAN_OPTIONS:
        assert name in LowerOptions.names()
        assert getattr(DEFAULT_OPTIONS, name) is True
        assert getattr(LowerOptions.none(), name) is False
    with pytest.raises(ValueError, match="unknown lowering optimisation"):
        DEFAULT_OPTIONS.without("no_such_option")


def test_debug_build_keeps_fb_bodies_in_their_own_calls():
    from stvm.debug.build import DEBUG_OPTIONS
    assert DEBUG_OPTIONS.inline_small_fbs is False and DEBUG_OPTIONS.cache_locals is False


STEP_MACHINE = """
FUNCTION_BLOCK Stepper
VAR_INPUT go : BOOL; END_VAR
VAR_OUTPUT done : BOOL; END_VAR
VAR step : INT; a : INT; b : INT; total : INT; i : INT; END_VAR
CASE step OF
  0: IF go THEN step := 10; END_IF;
  10: a := a + 1; a := a + 2; a := a + 3; step := 20;
  20: b := a * 2; b := b + a; b := b - 1; step := 30;
  30: FOR i := 1 TO 4 DO total := total + i; END_FOR; step := 40;
  40: done := TRUE; IF NOT go THEN step := 0; done := FALSE; END_IF;
END_CASE;
END_FUNCTION_BLOCK
PROGRAM Main
VAR s : Stepper; go : BOOL; done : BOOL; END_VAR
s(go := go, done => done);
END_PROGRAM
"""


def test_hot_path_cache_leaves_step_variables_on_the_instance():
    paths = ["Main.done", "Main.s.a", "Main.s.b", "Main.s.total", "Main.s.i", "Main.s.step"]
    on, off, seen = run_both(STEP_MACHINE, "hot_path_cache", 14, lambda k: {"Main.go": k % 7 < 5}, paths)
    # `a` and `b` are used 3-4 times, each in one of five steps: cached only without the option
    assert re.search(r"^\s+v_a = self\.v_a$", off, re.M)
    assert not re.search(r"^\s+v_a = self\.v_a$", on, re.M) and not re.search(r"^\s+v_b = self\.v_b$", on, re.M)
    # the FOR variable stays in a local (a range-FOR needs it) either way
    assert re.search(r"^\s+v_i = self\.v_i$", on, re.M) and "for v_i in _range" in on
    assert seen[-1]["Main.s.total"] > 0 and any(row["Main.done"] for row in seen)


COLD_FOR = """
FUNCTION_BLOCK Sender
VAR_INPUT go : BOOL; END_VAR
VAR_OUTPUT sum : BYTE; END_VAR
VAR step : INT; i : UINT; data : ARRAY[0..9] OF BYTE; END_VAR
IF go AND step = 0 THEN step := 10; END_IF;
IF step > 0 THEN
  CASE step OF
    10: data[3] := 7; data[5] := 9; step := 20;
    20: step := 30;
    30: step := 40;
    40: sum := 0; FOR i := 1 TO 9 DO sum := sum XOR data[i]; END_FOR; step := 50;
    50: IF NOT go THEN step := 0; END_IF;
  END_CASE;
END_IF;
END_FUNCTION_BLOCK
PROGRAM Main
VAR s : Sender; go : BOOL; sum : BYTE; END_VAR
s(go := go, sum => sum);
END_PROGRAM
"""


def test_hot_path_cache_leaves_a_cold_for_variable_on_the_instance():
    # the FOR runs in one step of five: a local would cost a load and a write-back on every call
    paths = ["Main.sum", "Main.s.i", "Main.s.step"]
    on, off, seen = run_both(COLD_FOR, "hot_path_cache", 16, lambda k: {"Main.go": k % 8 < 6}, paths)
    sender_on, sender_off = (code[code.index("_sender:"):code.index("class ", code.index("_sender:"))]
                             for code in (on, off))
    assert not re.search(r"^\s+v_i = self\.v_i$", sender_on, re.M) and "while self.v_i <= " in sender_on
    assert re.search(r"^\s+v_i = self\.v_i$", sender_off, re.M) and "for v_i in _range" in sender_off
    assert seen[-1]["Main.sum"] == 7 ^ 9 and seen[-1]["Main.s.i"] == 10


SOCKET_COPY = """
TYPE Addr : STRUCT port : UINT; ip : STRING[16]; END_STRUCT; END_TYPE
TYPE Sock : STRUCT handle : UDINT; src : Addr; dst : Addr; END_STRUCT; END_TYPE
FUNCTION_BLOCK User
VAR_INPUT s : Sock; END_VAR
VAR_OUTPUT h : UDINT; port : UINT; END_VAR
h := s.handle; port := s.dst.port;
END_FUNCTION_BLOCK
PROGRAM Main
VAR u : User; mine : Sock; h : UDINT; port : UINT; END_VAR
mine.handle := mine.handle + 1;
mine.dst.port := mine.dst.port + 2;
u(s := mine, h => h, port => port);
u(s := u.s);   (* a struct onto itself: a no-op *)
END_PROGRAM
"""


SOCKET_RUN = """
PROGRAM Main
VAR clr : SktClearBuf; send : SktTCPSend; rcv : SktTCPRcv; other : SktClearBuf; last : SktClose;
    sock : _sSOCKET; data : ARRAY[0..9] OF BYTE; got : UINT; n : INT; END_VAR
n := n + 1;
sock.Handle := sock.Handle + 1;
sock.DstAdr.PortNo := sock.DstAdr.PortNo + 2;
sock.SrcAdr.IpAdr := CONCAT('10.0.0.', INT_TO_STRING(n));
clr(Execute := FALSE, Socket := sock);
send(Execute := FALSE, Socket := sock, SendDat := data[0], Size := 3);
rcv(Execute := FALSE, Socket := sock, TimeOut := 0, Size := 4, RcvDat := data[0], RcvSize => got);
other(Execute := FALSE, Socket := sock);
last(Execute := FALSE, Socket := other.Socket);   (* a source inside a called instance *)
other(Execute := FALSE, Socket := send.Socket);
last(Execute := FALSE, Socket := other.Socket);   (* other was called since: read again *)
END_PROGRAM
"""


def test_share_struct_sources_copies_one_source_into_a_run_of_socket_fbs():
    paths = ["Main.clr.Socket.Handle", "Main.send.Socket.DstAdr.PortNo", "Main.rcv.Socket.SrcAdr.IpAdr",
             "Main.other.Socket.Handle", "Main.last.Socket.Handle", "Main.last.Socket.SrcAdr.IpAdr", "Main.got"]
    on, off, seen = run_both(SOCKET_RUN, "share_struct_sources", 4, lambda k: {}, paths)
    main_on, main_off = (code[code.rindex("_main:"):] for code in (on, off))
    # the first copy from `sock` keeps the five leaves, the next three store them; each other
    # source is read by its first copy
    assert main_on.count("_sd.v_handle = _h0 = _ss.v_handle") == 4 and main_on.count("_sd.v_handle = _h0\n") == 3
    assert "_h0" not in main_off
    # `other.Socket` is read again after `other` was called: nothing kept across that call
    assert main_on.count("_ss = self.v_other.v_socket") == 2 or main_on.count("_ss = v_other.v_socket") == 2
    assert seen[-1]["Main.last.Socket.Handle"] == 4 and seen[-1]["Main.rcv.Socket.SrcAdr.IpAdr"] == b"10.0.0.4"


def test_share_struct_sources_keeps_nothing_from_one_pou_to_the_next():
    source = """
PROGRAM First
VAR clr : SktClearBuf; sock : _sSOCKET; END_VAR
sock.Handle := 5;
clr(Execute := FALSE, Socket := sock);
clr(Execute := FALSE, Socket := sock);
END_PROGRAM
PROGRAM Second
VAR clr : SktClearBuf; sock : _sSOCKET; END_VAR
clr(Execute := FALSE, Socket := sock);
clr(Execute := FALSE, Socket := sock);
END_PROGRAM
CONFIGURATION C RESOURCE R ON PLC
TASK T(INTERVAL := T#10ms, PRIORITY := 1);
PROGRAM First_Instance WITH T : First;
PROGRAM Second_Instance WITH T : Second;
END_RESOURCE END_CONFIGURATION
"""
    project = load_with(source, DEFAULT_OPTIONS)
    code = project.lowered.source
    for name in ("_first:", "_second:"):
        body = code[code.index(name):]
        body = body[body.index("def __call__"):]
        body = body[:body.index("class ")] if "class " in body else body
        assert body.count("_sd.v_handle = _h0 = _ss.v_handle") == 1 and body.count("_sd.v_handle = _h0\n") == 1
    vm = project.start(scan="10ms")
    vm.scan()
    assert vm["First_Instance.clr.Socket.Handle"] == 5 and vm["Second_Instance.clr.Socket.Handle"] == 0


def test_share_struct_sources_not_in_the_debug_build():
    from stvm.debug.build import DEBUG_OPTIONS
    code = load_with(SOCKET_RUN, DEBUG_OPTIONS).lowered.source
    assert "_h0" not in code[code.rindex("_main:"):]


def test_inline_input_copy_copies_field_by_field_at_the_call():
    paths = ["Main.h", "Main.port", "Main.u.s.handle", "Main.u.s.dst.port", "Main.u.s.src.ip"]
    on, off, seen = run_both(SOCKET_COPY, "inline_input_copy", 5, lambda k: {}, paths)
    main_on = on[on.index("class P"):]
    assert "_sd = " in main_on and "v_u.v_s._assign(" not in main_on.replace("self.", "")
    assert ".v_s._assign(" in off[off.index("def __call__"):]
    assert seen[-1]["Main.h"] == 5 and seen[-1]["Main.u.s.dst.port"] == 10


def test_inline_input_copy_copies_a_struct_output_field_by_field():
    source = """
TYPE Addr : STRUCT port : UINT; ip : STRING[16]; END_STRUCT; END_TYPE
TYPE Sock : STRUCT handle : UDINT; src : Addr; dst : Addr; END_STRUCT; END_TYPE
FUNCTION_BLOCK Maker
VAR_OUTPUT s : Sock; END_VAR
s.handle := s.handle + 1; s.dst.port := s.dst.port + 2; s.src.ip := 'h';
END_FUNCTION_BLOCK
PROGRAM Main
VAR m : Maker; mine : Sock; socks : ARRAY[0..1] OF Sock; k : INT; END_VAR
m(s => mine);
k := 1 - k;
m(s => socks[k]);
END_PROGRAM
"""
    paths = ["Main.mine.handle", "Main.mine.dst.port", "Main.mine.src.ip", "Main.socks[0].handle", "Main.socks[1].dst.port"]
    on, off, seen = run_both(source, "inline_input_copy", 5, lambda k: {}, paths)
    main_on, main_off = on[on.index("class P"):], off[off.index("class P"):]
    assert "._assign(v_m.v_s)" not in main_on.replace("self.", "") and "_ss = v_m.v_s" in main_on
    assert "._assign(v_m.v_s)" in main_off.replace("self.", "")
    # calls 1, 3, ... 9 into mine, 2, 6, 10 into socks[1], 4, 8 into socks[0]
    assert seen[-1] == {"Main.mine.handle": 9, "Main.mine.dst.port": 18, "Main.mine.src.ip": b"h",
                        "Main.socks[0].handle": 8, "Main.socks[1].dst.port": 20}


def test_inline_input_copy_keeps_the_call_for_large_structs():
    fields = " ".join(f"f{i} : INT;" for i in range(40))
    source = f"""
TYPE Big : STRUCT {fields} END_STRUCT; END_TYPE
FUNCTION_BLOCK User
VAR_INPUT b : Big; END_VAR
VAR_OUTPUT last : INT; END_VAR
last := b.f39;
END_FUNCTION_BLOCK
PROGRAM Main
VAR u : User; big : Big; last : INT; END_VAR
big.f39 := big.f39 + 1;
u(b := big, last => last);
END_PROGRAM
"""
    on, _, seen = run_both(source, "inline_input_copy", 3, lambda k: {}, ["Main.last"])
    assert ".v_b._assign(" in on and seen[-1]["Main.last"] == 3


TIMERS = """
PROGRAM Main
VAR t : TON; start : BOOL; q : BOOL; et : TIME; END_VAR
t(IN := start, PT := T#30ms, Q => q, ET => et);
END_PROGRAM
"""


def test_direct_native_calls_skip_the_forwarding_call():
    on, off, seen = run_both(TIMERS, "direct_native_calls", 8, lambda k: {"Main.start": 1 <= k < 7},
                             ["Main.q", "Main.et"])
    assert "v_t._impl.call(v_t, _ctx)" in on.replace("self.", "")
    assert "_impl.call(" not in off[off.index("class P"):].replace("self._impl.call(self, _ctx)", "")
    assert [row["Main.q"] for row in seen] == [False, False, False, False, True, True, True, False]


def test_skip_quiet_native_calls_calls_a_socket_fb_only_when_execute_is_not_quiet():
    """SktClose on handle 0 fails at once (no network): Busy, then Error held while Execute
    stays TRUE, cleared by the call with Execute FALSE; the skipped calls change none of it."""
    source = """
PROGRAM Main
VAR c : SktClose; s : _sSOCKET; go : BOOL; busy : BOOL; err : BOOL; id : WORD; END_VAR
c(Execute := go, Socket := s, Busy => busy, Error => err, ErrorID => id);
END_PROGRAM
"""
    pattern = [False, True, True, True, False, False, True, False, False, True, True]
    on, off, seen = run_both(source, "skip_quiet_native_calls", len(pattern),
                             lambda k: {"Main.go": pattern[k]}, ["Main.busy", "Main.err", "Main.id"])
    assert "if v_c.v_execute is not v_c._impl.quiet: v_c._impl.call(v_c, _ctx)" in on.replace("self.", "")
    assert "._impl.quiet" not in off
    assert [row["Main.err"] for row in seen] == [False, False, True, True, False, False, False, True,
                                                 False, False, True]


def test_inline_small_fbs_not_used_when_a_pou_extends_the_fb():
    source = """
FUNCTION_BLOCK CountingTrig EXTENDS R_TRIG
VAR_OUTPUT calls : INT; END_VAR
SUPER^();
calls := calls + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR r : R_TRIG; x : BOOL; q : BOOL; END_VAR
x := NOT x;
r(CLK := x, Q => q);
END_PROGRAM
"""
    project = load_with(source, DEFAULT_OPTIONS)
    main = project.lowered.source[project.lowered.source.rindex("_main:"):].replace("self.", "")
    assert "v_r()" in main
    vm = project.start(scan="10ms")
    vm.run(cycles=3)
    assert vm["Main.q"] is True


ARRAY_FB = """
FUNCTION_BLOCK Filler
VAR_INPUT value : BYTE; END_VAR
VAR_IN_OUT buf : ARRAY[*] OF BYTE; END_VAR
VAR_OUTPUT size : DINT; END_VAR
buf[0] := value;
size := UPPER_BOUND(buf, 1) - LOWER_BOUND(buf, 1) + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : Filler; g : Filler; data : ARRAY[0..9] OF BYTE; other : ARRAY[1..4] OF BYTE; n : BYTE;
    size : DINT; gsize : DINT; END_VAR
n := n + 1;
f(value := n, buf := data[2], size => size);
IF n > 2 THEN f(value := n + 100, buf := other[1]); END_IF;
g(value := n, buf := data, size => gsize);
END_PROGRAM
"""


def test_reuse_array_refs_keeps_an_equal_reference():
    paths = ["Main.data[2]", "Main.data[0]", "Main.other[1]", "Main.size", "Main.gsize", "Main.f.size"]
    on, off, seen = run_both(ARRAY_FB, "reuse_array_refs", 5, lambda k: {}, paths)
    assert "(_ar := " in on and "(_ar := " not in off
    assert seen[-1]["Main.data[2]"] == 5 and seen[-1]["Main.other[1]"] == 105 and seen[-1]["Main.size"] == 8
    project = load_with(ARRAY_FB, DEFAULT_OPTIONS)
    vm = project.start(scan="10ms")
    vm.run(cycles=1)
    kept = vm.instances["main"][1].v_g.v_buf
    vm.run(cycles=3)   # the same list from the same element: the same object
    assert vm.instances["main"][1].v_g.v_buf is kept
    # f alternates between data[2] and other[1]: a new reference whenever the target changes
    assert vm.instances["main"][1].v_f.v_buf.data is vm.instances["main"][1].v_other


EDGES = """
PROGRAM Main
VAR r : R_TRIG; f : F_TRIG; latch : SR; x : BOOL; up : INT; down : INT; held : BOOL; END_VAR
r(CLK := x);
f(CLK := x);
IF r.Q THEN up := up + 1; END_IF;
IF f.Q THEN down := down + 1; END_IF;
latch(S1 := r.Q, R := f.Q, Q1 => held);
END_PROGRAM
"""


def test_inline_small_fbs_writes_the_edge_detectors_into_the_caller():
    pattern = [False, True, True, False, True, False, False, True]
    on, off, seen = run_both(EDGES, "inline_small_fbs", len(pattern), lambda k: {"Main.x": pattern[k]},
                             ["Main.up", "Main.down", "Main.held", "Main.r.Q", "Main.f.Q"])
    main_on, main_off = (code[code.index("class P"):] for code in (on, off))
    main_on, main_off = (code[code.rindex("_main:"):] for code in (main_on, main_off))
    assert "v_r()" not in main_on.replace("self.", "") and "v_r.v_m = " in main_on.replace("self.", "")
    assert "v_r()" in main_off.replace("self.", "")
    assert seen[-1]["Main.up"] == 3 and seen[-1]["Main.down"] == 2 and seen[-1]["Main.held"] is True


def test_inline_small_fbs_leaves_larger_or_richer_fbs_alone():
    source = """
FUNCTION_BLOCK Counter
VAR_INPUT inc : BOOL; END_VAR
VAR_OUTPUT n : INT; END_VAR
IF inc THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
PROGRAM Main
VAR c : Counter; t : TON; END_VAR
c(inc := TRUE);
t(IN := TRUE, PT := T#1s);
END_PROGRAM
"""
    code = load_with(source, DEFAULT_OPTIONS).lowered.source
    main = code[code.rindex("_main:"):].replace("self.", "")
    assert "v_c()" in main and "v_t._impl.call(" in main


TESTS = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(TESTS / "trace"))


@pytest.mark.parametrize("name", ["pnp_cycle", "connect_refused", "moveabs_rejected", "fault_drop"])
def test_thesis_goldens_without_the_scan_options(name):
    """The thesis traces are byte-identical with every scan option off (the defaults are checked
    by tests/trace/test_thesis_goldens.py). Compared here, never written."""
    from trace_helpers import SCENARIOS, THESIS
    from stvm.project import load
    from stvm.trace import TraceSpec, run_trace
    from stvm.trace.writers import to_jsonl
    with lowering(DEFAULT_OPTIONS.without(*SCAN_OPTIONS)):
        project = load([THESIS / "PnP_Example.st"], use_cache=False)
    assert "_impl.call(v_" not in project.lowered.source
    run = run_trace(TraceSpec([THESIS / "PnP_Example.st"], scenario=SCENARIOS / f"golden_{name}.toml"), project)
    assert to_jsonl(run.trace) == (TESTS / "golden" / f"{name}.jsonl").read_text(encoding="utf-8")
