"""Every ST statement, run on the VM: expected values after N scans (all cases share one load)."""

from __future__ import annotations

import pytest

from core_helpers import StCase, assert_case, case_params, run_cases

CASES = [
    # ---- assignment and the empty statement
    StCase("assign", """
PROGRAM S_Assign
VAR a : INT; b : INT := 4; c : BOOL; END_VAR
a := b * 2 + 1;
;
;;
c := a = 9;
END_PROGRAM""", {"a": 9, "c": True}),
    StCase("assign_chain_scans", """
PROGRAM S_Count
VAR n : DINT; END_VAR
n := n + 1;
END_PROGRAM""", {"n": 7}, cycles=7),

    StCase("empty_bodies", """
PROGRAM S_Empty
VAR i, x : INT := 3; END_VAR
IF x > 0 THEN ; END_IF;
IF x > 0 THEN ELSE x := 99; END_IF;
FOR i := 1 TO 3 DO END_FOR;
WHILE FALSE DO END_WHILE;
REPEAT UNTIL TRUE END_REPEAT;
CASE x OF 1: ; 3: ELSE x := 99; END_CASE;
x := x + 1;
END_PROGRAM""", {"x": 4}),

    # ---- IF / ELSIF / ELSE
    StCase("if_then", """
PROGRAM S_If1
VAR x : INT := 5; r : INT; END_VAR
IF x > 3 THEN r := 1; END_IF;
END_PROGRAM""", {"r": 1}),
    StCase("if_false_no_else", """
PROGRAM S_If2
VAR x : INT := 1; r : INT := 7; END_VAR
IF x > 3 THEN r := 1; END_IF;
END_PROGRAM""", {"r": 7}),
    StCase("if_elsif_chain", """
PROGRAM S_If3
VAR r1, r2, r3, r4 : INT; x : INT := 2; END_VAR
IF x = 1 THEN r1 := 1; ELSIF x = 2 THEN r1 := 2; ELSIF x = 2 THEN r1 := 3; ELSE r1 := 4; END_IF;
IF FALSE THEN r2 := 1; ELSIF FALSE THEN r2 := 2; ELSE r2 := 3; END_IF;
IF x < 0 THEN r3 := 1; ELSE r3 := 2; END_IF;
IF TRUE THEN IF x = 2 THEN r4 := 10; ELSE r4 := 20; END_IF; END_IF;
END_PROGRAM""", {"r1": 2, "r2": 3, "r3": 2, "r4": 10}),

    # ---- CASE
    StCase("case_lists_ranges_else", """
PROGRAM S_Case1
VAR c1, c2, c3, c4, c5, c6 : INT; sel : INT := 7; END_VAR
CASE sel OF 1, 2: c1 := 1; 3..8: c1 := 2; ELSE c1 := 3; END_CASE;
CASE 100 OF 1: c2 := 1; ELSE c2 := 9; END_CASE;
CASE 4 OF 1, 4, 9: c3 := 14; 2..3: c3 := 23; END_CASE;
CASE -5 OF -10..-1: c4 := 4; 0: c4 := 0; END_CASE;
CASE 50 OF 1: c5 := 1; END_CASE;
CASE sel OF 7: c6 := 1; c6 := c6 + 1; 8: c6 := 8; END_CASE;
END_PROGRAM""", {"c1": 2, "c2": 9, "c3": 14, "c4": 4, "c5": 0, "c6": 2}),
    StCase("case_range_bounds_inclusive", """
PROGRAM S_Case2
VAR lo, hi, out : INT; END_VAR
CASE 3 OF 3..8: lo := 1; END_CASE;
CASE 8 OF 3..8: hi := 1; END_CASE;
CASE 9 OF 3..8: out := 1; ELSE out := 2; END_CASE;
END_PROGRAM""", {"lo": 1, "hi": 1, "out": 2}),
    StCase("case_enum_labels", """
TYPE S_Color : (Red, Green, Blue); END_TYPE
PROGRAM S_Case3
VAR col : S_Color := Blue; c1, c2, c3 : INT; g : S_Color := S_Color#Green; END_VAR
CASE col OF Red: c1 := 1; Green, S_Color#Blue: c1 := 2; END_CASE;
CASE g OF S_Color#Red: c2 := 1; S_Color#Green: c2 := 2; ELSE c2 := 3; END_CASE;
CASE S_Color#Red OF Green: c3 := 1; ELSE c3 := 5; END_CASE;
END_PROGRAM""", {"c1": 2, "c2": 2, "c3": 5}),
    StCase("case_on_typed_selectors", """
PROGRAM S_Case4
VAR b : BYTE := 16#15; u : UINT := 300; r1, r2 : INT; END_VAR
CASE b OF 16#10..16#1F: r1 := 1; ELSE r1 := 2; END_CASE;
CASE u OF 0..255: r2 := 1; 256..65535: r2 := 2; END_CASE;
END_PROGRAM""", {"r1": 1, "r2": 2}),

    # ---- FOR
    StCase("for_sum", """
PROGRAM S_For1
VAR i, s : INT; END_VAR
s := 0;
FOR i := 1 TO 10 DO s := s + i; END_FOR;
END_PROGRAM""", {"s": 55}),
    StCase("for_by_positive_step", """
PROGRAM S_For2
VAR i, n, last : INT; END_VAR
FOR i := 0 TO 10 BY 3 DO n := n + 1; last := i; END_FOR;
END_PROGRAM""", {"n": 4, "last": 9}),
    StCase("for_negative_step", """
PROGRAM S_For3
VAR i : INT; s : DINT; END_VAR
FOR i := 10 TO 1 BY -3 DO s := s * 10 + i; END_FOR;
END_PROGRAM""", {"s": 10741}),
    StCase("for_zero_iterations", """
PROGRAM S_For4
VAR i, a, b : INT; END_VAR
FOR i := 5 TO 1 DO a := a + 1; END_FOR;
FOR i := 1 TO 5 BY -1 DO b := b + 1; END_FOR;
END_PROGRAM""", {"a": 0, "b": 0}),
    StCase("for_single_iteration", """
PROGRAM S_For5
VAR i, a, b : INT; END_VAR
FOR i := 3 TO 3 DO a := a + 1; END_FOR;
FOR i := 3 TO 3 BY -1 DO b := b + 1; END_FOR;
END_PROGRAM""", {"a": 1, "b": 1}),
    StCase("for_end_and_step_evaluated_once", """
PROGRAM S_For6
VAR i, n : INT; endv : INT := 5; step : INT := 2; END_VAR
FOR i := 1 TO endv BY step DO endv := 100; step := 1; n := n + 1; END_FOR;
END_PROGRAM""", {"n": 3}),
    StCase("for_nested", """
PROGRAM S_For7
VAR i, j, n : INT; END_VAR
FOR i := 1 TO 4 DO FOR j := i TO 4 DO n := n + 1; END_FOR; END_FOR;
END_PROGRAM""", {"n": 10}),
    StCase("for_dint_and_sint_loop_vars", """
PROGRAM S_For8
VAR d : DINT; s : SINT; total : DINT; cnt : INT; END_VAR
FOR d := 100000 TO 100004 DO total := total + d; END_FOR;
FOR s := -3 TO 3 DO cnt := cnt + 1; END_FOR;
END_PROGRAM""", {"total": 500010, "cnt": 7}),
    StCase("for_expressions_as_bounds", """
PROGRAM S_For9
VAR i, n : INT; a : INT := 2; b : INT := 3; END_VAR
FOR i := a * 2 TO a * b + 4 BY a DO n := n + 1; END_FOR;
END_PROGRAM""", {"n": 4}),

    # ---- WHILE / REPEAT
    StCase("while_loop", """
PROGRAM S_While1
VAR i, s : INT; END_VAR
i := 0; s := 0;
WHILE i < 5 DO i := i + 1; s := s + i; END_WHILE;
END_PROGRAM""", {"i": 5, "s": 15}),
    StCase("while_false_never_runs", """
PROGRAM S_While2
VAR n : INT; END_VAR
WHILE FALSE DO n := n + 1; END_WHILE;
END_PROGRAM""", {"n": 0}),
    StCase("repeat_runs_at_least_once", """
PROGRAM S_Repeat1
VAR n, j : INT; END_VAR
j := 0;
REPEAT n := n + 1; UNTIL TRUE END_REPEAT;
REPEAT j := j + 2; UNTIL j >= 7 END_REPEAT;
END_PROGRAM""", {"n": 1, "j": 8}),

    # ---- EXIT / CONTINUE
    StCase("exit_for", """
PROGRAM S_Exit1
VAR i, s : INT; END_VAR
FOR i := 1 TO 10 DO IF i = 4 THEN EXIT; END_IF; s := s + i; END_FOR;
END_PROGRAM""", {"s": 6}),
    StCase("exit_inner_loop_only", """
PROGRAM S_Exit2
VAR i, j, n : INT; END_VAR
FOR i := 1 TO 3 DO FOR j := 1 TO 3 DO IF j = 2 THEN EXIT; END_IF; n := n + 1; END_FOR; END_FOR;
END_PROGRAM""", {"n": 3}),
    StCase("exit_while_true_and_repeat", """
PROGRAM S_Exit3
VAR a, b : INT; END_VAR
WHILE TRUE DO a := a + 1; IF a = 7 THEN EXIT; END_IF; END_WHILE;
REPEAT b := b + 1; IF b = 3 THEN EXIT; END_IF; UNTIL FALSE END_REPEAT;
END_PROGRAM""", {"a": 7, "b": 3}),
    StCase("exit_from_case_inside_loop", """
PROGRAM S_Exit4
VAR i, last : INT; END_VAR
FOR i := 1 TO 10 DO CASE i OF 5: EXIT; END_CASE; last := i; END_FOR;
END_PROGRAM""", {"last": 4}),
    StCase("continue_for", """
PROGRAM S_Cont1
VAR i, s : INT; END_VAR
FOR i := 1 TO 10 DO IF i MOD 2 = 0 THEN CONTINUE; END_IF; s := s + i; END_FOR;
END_PROGRAM""", {"s": 25}),
    StCase("continue_while", """
PROGRAM S_Cont2
VAR j, s : INT; END_VAR
j := 0;
WHILE j < 5 DO j := j + 1; IF j = 3 THEN CONTINUE; END_IF; s := s + j; END_WHILE;
END_PROGRAM""", {"s": 12}),
    StCase("continue_repeat_still_tests_until", """
PROGRAM S_Cont3
VAR j, s : INT; END_VAR
REPEAT
  j := j + 1;
  IF j > 100 THEN EXIT; END_IF;       (* guard: a CONTINUE that skipped UNTIL would run to 101 *)
  IF j >= 3 THEN CONTINUE; END_IF;
  s := s + j;
UNTIL j >= 3 END_REPEAT;
END_PROGRAM""", {"j": 3, "s": 3}),
    StCase("continue_for_steps_variable", """
PROGRAM S_Cont4
VAR i, n : INT; END_VAR
FOR i := 10 TO 0 BY -2 DO CONTINUE; n := 99; END_FOR;
n := n + i;
END_PROGRAM""", {"n": -2}),

    # ---- RETURN
    StCase("return_from_program_body", """
PROGRAM S_Ret1
VAR n, after : INT; END_VAR
n := n + 1;
IF n >= 2 THEN RETURN; END_IF;
after := after + 1;
END_PROGRAM""", {"n": 4, "after": 1}, cycles=4),
    StCase("return_inside_loop_leaves_body", """
PROGRAM S_Ret2
VAR i, s, after : INT; END_VAR
FOR i := 1 TO 10 DO s := s + 1; IF i = 3 THEN RETURN; END_IF; END_FOR;
after := 1;
END_PROGRAM""", {"s": 3, "after": 0}),
    StCase("return_from_function_and_fb", """
FUNCTION S_Early : INT
VAR_INPUT x : INT; END_VAR
S_Early := 1;
IF x > 0 THEN RETURN; END_IF;
S_Early := 2;
END_FUNCTION
FUNCTION_BLOCK S_EarlyFB
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
q := 1;
IF x > 0 THEN RETURN; END_IF;
q := 2;
END_FUNCTION_BLOCK
PROGRAM S_Ret3
VAR a, b, c, d : INT; f1, f2 : S_EarlyFB; END_VAR
a := S_Early(5); b := S_Early(x := -1);
f1(x := 5); f2(x := 0);
c := f1.q; d := f2.q;
END_PROGRAM""", {"a": 1, "b": 2, "c": 1, "d": 2}),

    # ---- statements in sequence see each other's effects; top to bottom
    StCase("order_top_to_bottom", """
PROGRAM S_Order
VAR a, b, c : INT; END_VAR
a := 1; b := a + 1; a := 10; c := a + b;
END_PROGRAM""", {"c": 12}),
]

RESULTS: dict | None = None


@pytest.fixture(scope="module")
def results():
    return run_cases(CASES)


@pytest.mark.parametrize("case", case_params(CASES))
def test_statement(case, results):
    assert_case(case, results[case.name])
