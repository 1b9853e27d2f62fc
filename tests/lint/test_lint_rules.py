"""Every rule on its documented example (reported) and fixed version (clean under every rule),
plus targeted positive and negative cases per rule. Expected lines are 1-based in the snippet."""

from __future__ import annotations

import pytest

from lint_helpers import findings, lines
from stvm.lint.registry import all_rules

RULES = all_rules()


@pytest.mark.parametrize("rule", RULES, ids=[r.code for r in RULES])
def test_documented_example_is_reported(rule):
    assert [f.code for f in findings(rule.example, rule.code)], rule.example


@pytest.mark.parametrize("rule", RULES, ids=[r.code for r in RULES])
def test_documented_fix_is_clean_under_every_rule(rule):
    assert [(f.code, f.span.line, f.message) for f in findings(rule.fixed)] == []


def test_rule_codes_are_unique_stable_and_documented():
    codes = [r.code for r in RULES]
    assert len(codes) == len(set(codes)) == 20
    for r in RULES:
        assert r.code[:2] == "SA" and len(r.code) == 5 and r.summary and r.rationale and r.name
        assert "\n" not in r.summary


FB = """FUNCTION_BLOCK T
{decls}
{body}
END_FUNCTION_BLOCK
"""


def fb(decls: str, body: str) -> str:
    return FB.format(decls=decls, body=body)


SEQ = """FUNCTION_BLOCK Conn
VAR_INPUT start, timeout, stop : BOOL; END_VAR
VAR_OUTPUT Error : BOOL; END_VAR
VAR_IN_OUT Link : BOOL; END_VAR
VAR step : INT; connect : SktTCPConnect; close : SktClose; sock : _sSOCKET; connectExe, closeExe : BOOL; END_VAR
CASE step OF
0: IF start THEN connectExe := TRUE; Link := TRUE; Error := FALSE; step := 10; END_IF;
10: IF connect.Done THEN
        connectExe := FALSE;
        step := 20;
    ELSIF connect.Error THEN
        Link := FALSE; Error := TRUE; step := 0;
    ELSIF timeout THEN
        {timeout_path}
    END_IF;
20: IF stop THEN step := 30; END_IF;
30: closeExe := TRUE; Link := FALSE;
    IF close.Done THEN closeExe := FALSE; step := 0; END_IF;
END_CASE;
connect(Execute := connectExe, SrcTcpPort := 0, DstAdr := '10.0.0.1', DstTcpPort := 5890, Socket => sock);
close(Execute := closeExe, Socket := sock);
END_FUNCTION_BLOCK
"""

CASES = [
    # ---- SA101 read-before-write
    ("SA101", "function local read on the ELSE path",
     """FUNCTION F : INT
VAR_INPUT c : BOOL; END_VAR
VAR tmp : INT; END_VAR
IF c THEN tmp := 1; END_IF;
F := tmp;
END_FUNCTION""", [5]),
    ("SA101", "function result read before it is assigned",
     """FUNCTION F : INT
VAR_INPUT c : INT; END_VAR
F := F + c;
END_FUNCTION""", [3]),
    ("SA101", "written on both paths", """FUNCTION F : INT
VAR_INPUT c : BOOL; END_VAR
VAR tmp : INT; END_VAR
IF c THEN tmp := 1; ELSE tmp := 2; END_IF;
F := tmp;
END_FUNCTION""", []),
    ("SA101", "FB locals persist between calls: reading them is fine",
     fb("VAR_OUTPUT y : INT; END_VAR VAR count : INT; END_VAR", "count := count + 1; y := count;"), []),
    ("SA101", "a temp passed as an in-out output buffer counts as written",
     fb("VAR_INPUT s : STRING[10]; END_VAR VAR_OUTPUT y : BYTE; END_VAR VAR_TEMP buf : ARRAY[0..15] OF BYTE; END_VAR",
        "ToAryByte(s, _eBYTE_ORDER#_LOW_HIGH, buf[0]); y := buf[0];"), []),
    # ---- SA102 unused-write
    ("SA102", "FB local only written", fb("VAR_INPUT a : INT; END_VAR VAR scratch : INT; END_VAR", "scratch := a;"), [2]),
    ("SA102", "output binding target never read",
     fb("VAR t : TON; q : BOOL; END_VAR", "t(IN := TRUE, PT := T#1s, Q => q);"), [2]),
    ("SA102", "program variables are read by the HMI and traces",
     "PROGRAM Main\nVAR x : INT; END_VAR\nx := 1;\nEND_PROGRAM\n", []),
    ("SA102", "read later", fb("VAR_OUTPUT y : INT; END_VAR VAR a : INT; END_VAR", "a := 1; y := a;"), []),
    # ---- SA103 output-unassigned
    ("SA103", "function output missing on a path", """FUNCTION F : BOOL
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT neg : BOOL; END_VAR
F := a > 0;
IF a < 0 THEN neg := TRUE; END_IF;
END_FUNCTION""", [6]),
    ("SA103", "FB output never assigned", fb("VAR_OUTPUT Done, Busy : BOOL; END_VAR", "Done := TRUE;"), [2]),
    ("SA103", "function result assigned on every path", """FUNCTION F : INT
VAR_INPUT a : INT; END_VAR
IF a > 0 THEN F := 1; ELSE F := 0; END_IF;
END_FUNCTION""", []),
    ("SA103", "RETURN after assigning", """FUNCTION F : INT
VAR_INPUT a : INT; END_VAR
F := 0;
IF a > 0 THEN F := 1; RETURN; END_IF;
END_FUNCTION""", []),
    # ---- SA104 fb-called-twice
    ("SA104", "called in a loop", fb("VAR_OUTPUT q : BOOL; END_VAR VAR t : R_TRIG; i : INT; END_VAR",
                                     "FOR i := 1 TO 3 DO t(CLK := TRUE); END_FOR; q := t.Q;"), [3]),
    ("SA104", "two calls on one path", fb("VAR_INPUT a : BOOL; END_VAR VAR_OUTPUT q : BOOL; END_VAR VAR t : R_TRIG; END_VAR",
                                          "t(CLK := a);\nt(CLK := NOT a); q := t.Q;"), [4]),
    ("SA104", "calls in exclusive branches",
     fb("VAR_INPUT a : BOOL; END_VAR VAR_OUTPUT q : BOOL; END_VAR VAR t : R_TRIG; END_VAR",
        "IF a THEN t(CLK := TRUE); ELSE t(CLK := FALSE); END_IF; q := t.Q;"), []),
    ("SA104", "two different instances of one array",
     fb("VAR_OUTPUT q : BOOL; END_VAR VAR t : ARRAY[0..1] OF R_TRIG; END_VAR",
        "t[0](CLK := TRUE); t[1](CLK := TRUE); q := t[0].Q AND t[1].Q;"), []),
    ("SA104", "reset call, then a new start in the same scan",
     fb("VAR_INPUT go : BOOL; END_VAR VAR_OUTPUT q : BOOL; END_VAR VAR c : SktClose; s : _sSOCKET; END_VAR",
        "c(Execute := go, Socket := s);\nIF c.Done THEN c(Execute := FALSE, Socket := s); c(Execute := TRUE, Socket := s); END_IF;\nq := c.Done;"), []),
    ("SA304", "CONCAT of a digit under a guard fits", fb("VAR_INPUT tag : UINT; END_VAR VAR_OUTPUT s : STRING[3]; END_VAR",
                                                        "IF tag < 10 THEN s := CONCAT('0', UINT_TO_STRING(tag)); END_IF;"), []),
    # ---- SA105 execute-level
    ("SA105", "level start", fb("VAR_INPUT Execute : BOOL; END_VAR VAR_OUTPUT Busy : BOOL; END_VAR",
                                "IF Execute THEN Busy := TRUE; END_IF;"), [3]),
    ("SA105", "xExecute = TRUE", fb("VAR_INPUT xExecute : BOOL; END_VAR VAR_OUTPUT Busy : BOOL; END_VAR",
                                    "IF xExecute = TRUE THEN Busy := TRUE; END_IF;"), [3]),
    ("SA105", "NOT Execute resets (allowed)", fb("VAR_INPUT Execute : BOOL; END_VAR VAR_OUTPUT Done : BOOL; END_VAR",
                                                 "IF NOT Execute THEN Done := FALSE; END_IF;"), []),
    ("SA105", "edge through R_TRIG and pass-through to an inner block (allowed)",
     fb("VAR_INPUT Execute : BOOL; END_VAR VAR_OUTPUT Done : BOOL; END_VAR VAR e : R_TRIG; inner : SktClose; s : _sSOCKET; END_VAR",
        "e(CLK := Execute); IF e.Q THEN Done := FALSE; END_IF; inner(Execute := Execute, Socket := s); Done := inner.Done;"), []),
    # ---- SA201 index-out-of-bounds
    ("SA201", "loop one past the end", fb("VAR_OUTPUT s : INT; END_VAR VAR a : ARRAY[0..9] OF INT; i : INT; END_VAR",
                                          "FOR i := 0 TO 10 DO s := s + a[i]; END_FOR;"), [3]),
    ("SA201", "offset index", fb("VAR_OUTPUT s : INT; END_VAR VAR a : ARRAY[1..5] OF INT; i : INT; END_VAR",
                                 "FOR i := 1 TO 5 DO s := s + a[i + 1]; END_FOR;"), [3]),
    ("SA201", "guarded index", fb("VAR_INPUT k : INT; END_VAR VAR_OUTPUT s : INT; END_VAR VAR a : ARRAY[0..9] OF INT; END_VAR",
                                  "IF k >= 0 AND k <= 9 THEN s := a[k]; END_IF;"), []),
    ("SA201", "unchecked input (whole type): not reported",
     fb("VAR_INPUT k : INT; END_VAR VAR_OUTPUT s : INT; END_VAR VAR a : ARRAY[0..9] OF INT; END_VAR", "s := a[k];"), []),
    ("SA201", "subrange index fits",
     fb("VAR_INPUT k : INT(0..9); END_VAR VAR_OUTPUT s : INT; END_VAR VAR a : ARRAY[0..9] OF INT; END_VAR", "s := a[k];"), []),
    ("SA201", "subrange index too wide",
     fb("VAR_INPUT k : INT(0..10); END_VAR VAR_OUTPUT s : INT; END_VAR VAR a : ARRAY[0..9] OF INT; END_VAR", "s := a[k];"), [3]),
    # ---- SA202 integer-overflow
    ("SA202", "INT times constant", fb("VAR_INPUT a : INT; END_VAR VAR_OUTPUT y : INT; END_VAR", "y := a * 1000;"), [3]),
    ("SA202", "typed constant expression", fb("VAR_OUTPUT y : INT; END_VAR", "y := INT#30000 + INT#30000;"), [3]),
    ("SA202", "known small range", fb("VAR_INPUT a : INT; END_VAR VAR_OUTPUT y : INT; END_VAR",
                                      "IF a >= 0 AND a <= 30 THEN y := a * 1000; END_IF;"), []),
    ("SA202", "untyped literals fold in DINT/LINT", fb("VAR_OUTPUT y : LINT; END_VAR", "y := 100000 * 100000;"), []),
    ("SA202", "sum of two variables is not reported", fb("VAR_INPUT a, b : INT; END_VAR VAR_OUTPUT y : INT; END_VAR",
                                                         "y := a + b;"), []),
    # ---- SA203 narrowing-conversion
    ("SA203", "INT into UINT", fb("VAR_INPUT a : INT; END_VAR VAR_OUTPUT y : UINT; END_VAR", "y := a;"), [3]),
    ("SA203", "explicit narrowing of a known wide range",
     fb("VAR_INPUT a : INT; END_VAR VAR_OUTPUT y : SINT; END_VAR", "IF a > 200 THEN y := INT_TO_SINT(a); END_IF;"), [3]),
    ("SA203", "INT known non-negative into UINT", fb("VAR_INPUT a : INT; END_VAR VAR_OUTPUT y : UINT; END_VAR",
                                                     "IF a >= 0 THEN y := a; END_IF;"), []),
    ("SA203", "explicit conversion of an unknown input (the author chose)",
     fb("VAR_INPUT a : DINT; END_VAR VAR_OUTPUT y : INT; END_VAR", "y := DINT_TO_INT(a);"), []),
    # ---- SA204 division-by-zero
    ("SA204", "MOD by input", fb("VAR_INPUT a, b : INT; END_VAR VAR_OUTPUT y : INT; END_VAR", "y := a MOD b;"), [3]),
    ("SA204", "divisor assigned 0 on a path", fb("VAR_INPUT a : INT; c : BOOL; END_VAR VAR_OUTPUT y : INT; END_VAR VAR d : INT; END_VAR",
                                                  "d := 0; IF c THEN d := 4; END_IF; y := a / d;"), [3]),
    ("SA204", "divisor known positive", fb("VAR_INPUT a, b : INT; END_VAR VAR_OUTPUT y : INT; END_VAR",
                                           "IF b > 0 THEN y := a / b; END_IF;"), []),
    ("SA204", "constant divisor", fb("VAR_INPUT a : INT; END_VAR VAR_OUTPUT y : INT; END_VAR", "y := a / 10;"), []),
    # ---- SA301 hex-unpadded
    ("SA301", "WORD_TO_STRING", fb("VAR_INPUT w : WORD; END_VAR VAR_OUTPUT s : STRING[8]; END_VAR", "s := WORD_TO_STRING(w);"), [3]),
    ("SA301", "value known below 16", fb("VAR_INPUT b : BYTE; END_VAR VAR_OUTPUT s : STRING[8]; END_VAR",
                                         "IF b < 16 THEN s := BYTE_TO_STRING(b); END_IF;"), [3]),
    ("SA301", "value known >= 16", fb("VAR_INPUT b : BYTE; END_VAR VAR_OUTPUT s : STRING[8]; END_VAR",
                                      "IF b >= 16 THEN s := BYTE_TO_STRING(b); END_IF;"), []),
    ("SA301", "padded by a LEN test", fb("VAR_INPUT b : BYTE; END_VAR VAR_OUTPUT s : STRING[8]; END_VAR",
                                         "s := BYTE_TO_STRING(b); IF LEN(s) < 2 THEN s := CONCAT('0', s); END_IF;"), []),
    # ---- SA302 position-decimals
    ("SA302", "REAL_TO_INT of a coordinate before formatting",
     fb("VAR_INPUT Pos : ARRAY[0..2] OF REAL; END_VAR VAR_OUTPUT s : STRING[16]; END_VAR", "s := INT_TO_STRING(REAL_TO_INT(Pos[0]));"), [3]),
    ("SA302", "a speed with 0 decimals is not a position",
     fb("VAR_INPUT speed : REAL; END_VAR VAR_OUTPUT s : STRING[32]; END_VAR",
        "s := RealToFormatString(In := speed, Exponent := FALSE, Sign := FALSE, MinLen := 1, DecPlace := 0);"), []),
    ("SA302", "default DecPlace is 6", fb("VAR_INPUT X : REAL; END_VAR VAR_OUTPUT s : STRING[64]; END_VAR",
                                          "s := RealToFormatString(In := X);"), []),
    # ---- SA303 fixed-receive-size
    ("SA303", "constant count", fb("VAR_OUTPUT t : STRING[300]; END_VAR VAR r : SktTCPRcv; s : _sSOCKET; d : ARRAY[0..255] OF BYTE; n : UINT; END_VAR",
                                   "r(Execute := TRUE, Socket := s, Size := 256, RcvDat := d[0], RcvSize => n); t := AryToString(d[0], 200); t := CONCAT(t, UINT_TO_STRING(n));"), [3]),
    ("SA303", "not a receive buffer", fb("VAR_OUTPUT t : STRING[300]; END_VAR VAR d : ARRAY[0..255] OF BYTE; END_VAR",
                                         "t := AryToString(d[0], 256);"), []),
    # ---- SA304 concat-overflow
    ("SA304", "literal pieces", fb("VAR_OUTPUT s : STRING[5]; END_VAR", "s := CONCAT('abc', 'def');"), [3]),
    ("SA304", "fits", fb("VAR_INPUT a : STRING[10]; END_VAR VAR_OUTPUT s : STRING[32]; END_VAR", "s := CONCAT(a, '-', a);"), []),
    ("SA304", "assigned values bound the length", fb("VAR_OUTPUT s : STRING[16]; END_VAR VAR part : STRING[256]; END_VAR",
                                                     "part := 'abc'; s := CONCAT(part, part);"), []),
    # ---- SA401 case-enum-incomplete
    ("SA401", "ELSE present", """TYPE eM : (A, B, C); END_TYPE
FUNCTION_BLOCK T
VAR_INPUT m : eM; END_VAR VAR_OUTPUT y : INT; END_VAR
CASE m OF A: y := 1; ELSE y := 0; END_CASE;
END_FUNCTION_BLOCK""", []),
    ("SA401", "integer selector is not checked", fb("VAR_INPUT m : INT; END_VAR VAR_OUTPUT y : INT; END_VAR",
                                                    "CASE m OF 1: y := 1; END_CASE;"), []),
    ("SA401", "range label covers all", """TYPE eM : (A, B, C); END_TYPE
FUNCTION_BLOCK T
VAR_INPUT m : eM; END_VAR VAR_OUTPUT y : INT; END_VAR
CASE m OF A: y := 1; B, C: y := 2; END_CASE;
END_FUNCTION_BLOCK""", []),
    ("SA401", "enum in a namespace, one enumerator missing", r"""NAMESPACE Lib
TYPE eM : (A, B, C); END_TYPE
END_NAMESPACE
FUNCTION_BLOCK T
VAR_INPUT m : Lib\eM; END_VAR VAR_OUTPUT y : INT; END_VAR
CASE m OF Lib\eM#A: y := 1; Lib\eM#B: y := 2; END_CASE;
END_FUNCTION_BLOCK""", [6]),
    # ---- SA402 dead-branch
    ("SA402", "always TRUE makes ELSE dead", fb("VAR_INPUT a : USINT; END_VAR VAR_OUTPUT y : BOOL; END_VAR",
                                                "IF a >= 0 THEN y := TRUE; ELSE y := FALSE; END_IF;"), [3]),
    ("SA402", "CASE label outside the selector's range",
     fb("VAR_INPUT a : BOOL; END_VAR VAR_OUTPUT y : INT; END_VAR VAR step : INT; END_VAR",
        "CASE step OF\n0: IF a THEN step := 10; END_IF;\n10: step := 0;\n99: y := 1;\nEND_CASE;"), [6]),
    ("SA402", "state set in another scan is reachable",
     fb("VAR_INPUT a : BOOL; END_VAR VAR_OUTPUT y : INT; END_VAR VAR step : INT; END_VAR",
        "CASE step OF\n0: IF a THEN step := 10; END_IF;\n10: y := 1; step := 0;\nEND_CASE;"), []),
    ("SA402", "a program variable the program never assigns is set from outside",
     "PROGRAM Main\nVAR x : INT; y : BOOL; END_VAR\nIF x > 5 THEN y := TRUE; END_IF;\nEND_PROGRAM\n", []),
    ("SA402", "a program variable the program assigns is internal",
     "PROGRAM Main\nVAR x : INT; y : BOOL; END_VAR\nx := 1;\nIF x > 5 THEN y := TRUE; END_IF;\nEND_PROGRAM\n", [4]),
    ("SA402", "globals can be written by others",
     "VAR_GLOBAL g : INT; END_VAR\nPROGRAM Main\nVAR_EXTERNAL g : INT; END_VAR VAR y : BOOL; END_VAR\n"
     "IF g > 5 THEN y := TRUE; END_IF;\nEND_PROGRAM\n", []),
    # ---- SA403 state-overwritten
    ("SA403", "unconditional overwrite", fb("VAR step : INT; END_VAR VAR_INPUT a : BOOL; END_VAR",
                                            "CASE step OF\n0: step := 5; step := 10;\n5, 10: IF a THEN step := 0; END_IF;\nEND_CASE;"), [4]),
    ("SA403", "read in between", fb("VAR step : INT; END_VAR VAR_OUTPUT y : INT; END_VAR VAR_INPUT a : BOOL; END_VAR",
                                    "CASE step OF\n0: step := 5; y := step; step := 10;\n5, 10: IF a THEN step := 0; END_IF;\nEND_CASE;"), []),
    ("SA403", "not a state variable", fb("VAR_OUTPUT y : INT; END_VAR VAR_INPUT a : BOOL; END_VAR",
                                         "y := 1; y := 2;"), []),
    # ---- SA404 for-variable-written
    ("SA404", "passed as an output target", fb("VAR i : INT; t : TON; END_VAR VAR_OUTPUT e : TIME; END_VAR",
                                               "FOR i := 0 TO 3 DO t(IN := TRUE, PT := T#1s, ET => e); i := 5; END_FOR;"), [3]),
    ("SA404", "nested loop reuses the variable", fb("VAR i : INT; END_VAR VAR_OUTPUT y : INT; END_VAR",
                                                    "FOR i := 0 TO 3 DO\nFOR i := 0 TO 2 DO y := y + 1; END_FOR;\nEND_FOR;"), [4]),
    ("SA404", "only read", fb("VAR i : INT; END_VAR VAR_OUTPUT y : INT; END_VAR", "FOR i := 0 TO 3 DO y := y + i; END_FOR;"), []),
    # ---- SA501 socket-leak / SA502 flag-not-cleared: a step sequence
    ("SA501", "connect pending when a timeout ends the sequence", SEQ.format(timeout_path="Error := TRUE;"), [14]),
    ("SA501", "the timeout closes first", SEQ.format(timeout_path="closeExe := TRUE; Error := TRUE;"), []),
    ("SA501", "the timeout moves to the closing step", SEQ.format(timeout_path="Error := TRUE; step := 30;"), []),
    ("SA502", "busy flag not cleared by the timeout", SEQ.format(timeout_path="Error := TRUE;"), [14]),
    ("SA502", "busy flag cleared by the timeout", SEQ.format(timeout_path="Link := FALSE; closeExe := TRUE; Error := TRUE;"), []),
    # ---- SA405 real-equality
    ("SA405", "<> on LREAL", fb("VAR_INPUT a, b : LREAL; END_VAR VAR_OUTPUT y : BOOL; END_VAR", "y := a <> b;"), [3]),
    ("SA405", "integers", fb("VAR_INPUT a, b : INT; END_VAR VAR_OUTPUT y : BOOL; END_VAR", "y := a = b;"), []),
    ("SA405", "ordering on REAL", fb("VAR_INPUT a, b : REAL; END_VAR VAR_OUTPUT y : BOOL; END_VAR", "y := a < b;"), []),
]


@pytest.mark.parametrize(("code", "what", "source", "expected"), CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_rule_case(code, what, source, expected):
    assert lines(source, code) == expected


def test_every_rule_has_a_targeted_positive_and_negative_case():
    for r in RULES:
        mine = [c for c in CASES if c[0] == r.code]
        assert any(c[3] for c in mine) and any(not c[3] for c in mine), r.code


def test_setting_dependent_rules_follow_the_sysmac_settings():
    from stvm.settings import SysmacSettings
    DEFAULT_SETTINGS = SysmacSettings(dialect="sysmac")   # the rules are about Omron's conversions
    source = fb("VAR_INPUT b : BYTE; END_VAR VAR_OUTPUT s : STRING[8]; END_VAR", "s := BYTE_TO_STRING(b);")
    [finding] = findings(source, "SA301", settings=DEFAULT_SETTINGS)
    assert "hexadecimal without leading zeros (byte_to_string_format=hex_nopad)" in finding.message
    padded = DEFAULT_SETTINGS.with_overrides(["byte_to_string_format=hex_pad2"])
    assert findings(source, "SA301", settings=padded) == []
    checksum = next(r for r in RULES if r.code == "SA201").example
    [finding] = findings(checksum, "SA201", settings=DEFAULT_SETTINGS)
    assert "the terminating 16#00 ToAryByte adds (toarybyte_string_model=text_nul)" in finding.message
    stale = DEFAULT_SETTINGS.with_overrides(["toarybyte_string_model=text"])
    [finding] = findings(checksum, "SA201", settings=stale)
    assert "a stale byte (toarybyte_string_model=text)" in finding.message
