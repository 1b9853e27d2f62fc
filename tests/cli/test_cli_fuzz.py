"""Bad input never reaches the user as a Python traceback.

A few hundred mutated ST programs (deterministic seed) go through `stvm run` and `stvm check`
via `stvm.cli.main` with captured output: the exit code is always one of 0/1/2/3 and stderr never
contains 'Traceback'. Seeds and the insertion vocabulary have no loops, so a mutant cannot hang
the run; a watchdog turns a hang into a failure anyway.
"""

from __future__ import annotations

import random
import re
import signal

import pytest

from core_helpers import cli, write_st

SEEDS = [
    """PROGRAM Main
VAR x : INT := 1; y : DINT; b : BOOL; s : STRING[10] := 'abc'; r : REAL := 1.5; END_VAR
x := x + 1;
y := x * 1000;
IF x > 3 THEN b := TRUE; ELSIF x = 2 THEN b := FALSE; ELSE x := 0; END_IF;
s := CONCAT(s, 'd');
r := r * 2.0 + x;
END_PROGRAM
""",
    """TYPE Color : (Red, Green, Blue); Pt : STRUCT x : INT := 1; y : INT; END_STRUCT; END_TYPE
PROGRAM Main
VAR c : Color := Green; p : Pt; q : Pt; a : ARRAY[1..3] OF INT := [1, 2, 3]; i : INT := 2; k : INT; END_VAR
CASE c OF Red: k := 1; Green, Color#Blue: k := 2; ELSE k := 3; END_CASE;
q := p; q.x := a[i] + 4;
a[i] := q.x MOD 3;
c := Color#Blue;
END_PROGRAM
""",
    """FUNCTION_BLOCK Acc
VAR_INPUT step : INT := 1; END_VAR
VAR_OUTPUT total : DINT; END_VAR
VAR_IN_OUT ref : INT; END_VAR
total := total + step; ref := ref + 1;
END_FUNCTION_BLOCK
FUNCTION Twice : INT
VAR_INPUT v : INT; END_VAR
Twice := v * 2;
END_FUNCTION
PROGRAM Main
VAR f : Acc; n : INT; r : INT; t : TON; done : BOOL; END_VAR
f(step := Twice(3), ref := n, total => r);
t(IN := TRUE, PT := T#30ms);
done := t.Q AND f.total > 5;
END_PROGRAM
""",
    """VAR_GLOBAL g : INT := 7; END_VAR
VAR_GLOBAL CONSTANT K : INT := 3; END_VAR
PROGRAM Main
VAR_EXTERNAL g : INT; END_VAR
VAR_EXTERNAL CONSTANT K : INT; END_VAR
VAR w : WORD := 16#00F0; by : BYTE; t : TIME := T#1s500ms; d : DT := DT#2024-01-01-00:00:00; u : UINT; END_VAR
g := g + K;
w := w XOR 16#FFFF; by := BYTE#16#0A;
t := t + T#10ms; d := d + t;
u := g;
END_PROGRAM
""",
    """CONFIGURATION C
  RESOURCE R ON PLC
    TASK Fast (INTERVAL := T#10ms, PRIORITY := 1);
    TASK Slow (INTERVAL := T#30ms, PRIORITY := 2);
    PROGRAM A WITH Fast : P1;
    PROGRAM B WITH Slow : P2;
  END_RESOURCE
END_CONFIGURATION
PROGRAM P1 VAR n : INT; END_VAR n := n + 1; END_PROGRAM
PROGRAM P2 VAR n : INT; s : STRING := '$$TMSTA,2,00,*41$R$L'; END_VAR n := n - 1; END_PROGRAM
""",
    r"""NAMESPACE Lib
TYPE eMode : (Line := 0, PTP := 1); stConn : STRUCT Count : INT; Mode : eMode := PTP; END_STRUCT; END_TYPE
END_NAMESPACE
PROGRAM Main
VAR conn : Lib\stConn; m : Lib\eMode := \\Lib\eMode#Line; z : INT; q : INT; arr : ARRAY[-1..1, 0..1] OF INT; END_VAR
conn.Count := conn.Count + 1;
IF m = Lib\eMode#Line THEN q := 10 / (conn.Count - z); END_IF;
arr[0, 1] := q;
END_PROGRAM
""",
]

LOOP_SEED = """PROGRAM Main
VAR i, s : INT; j : INT; END_VAR
FOR i := 1 TO 10 BY 2 DO s := s + i; IF s > 5 THEN EXIT; END_IF; END_FOR;
WHILE j < 3 DO j := j + 1; CONTINUE; END_WHILE;
REPEAT j := j - 1; UNTIL j <= 0 END_REPEAT;
END_PROGRAM
"""

VOCAB = [";", ":=", ":", ",", ".", "..", "(", ")", "[", "]", "#", "'", '"', "$", "\\", "\\\\", "=>", "^", "&",
         "+", "-", "*", "/", "**", "<", ">", "<=", ">=", "<>", "=", "(*", "*)", "//", "{", "}", "%IX0.0",
         "IF", "THEN", "ELSE", "ELSIF", "END_IF", "CASE", "OF", "END_CASE", "RETURN", "EXIT", "CONTINUE",
         "VAR", "END_VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_GLOBAL", "VAR_EXTERNAL",
         "CONSTANT", "RETAIN", "PROGRAM", "END_PROGRAM", "FUNCTION", "END_FUNCTION", "FUNCTION_BLOCK",
         "END_FUNCTION_BLOCK", "TYPE", "END_TYPE", "STRUCT", "END_STRUCT", "ARRAY", "STRING", "NAMESPACE",
         "CONFIGURATION", "RESOURCE", "TASK", "WITH", "AND", "OR", "XOR", "NOT", "MOD", "TRUE", "FALSE",
         "INT", "DINT", "LINT", "REAL", "LREAL", "BOOL", "BYTE", "TIME", "DT", "TOD", "DATE", "WSTRING",
         "0", "-1", "1.5e308", "1e999", "99999999999999999999999", "16#FFFF_FFFF_FFFF_FFFF", "2#102",
         "T#1h", "T#-5s", "T#", "D#2024-02-30", "TOD#25:00:00", "DT#2024-01-01-00:00:00", "INT#70000",
         "BYTE#16#1FF", "Color#Pink", "'$Q'", "'$'", "''", "'abc", "\"x\"", "x", "n", "Main", "self",
         "__import__", "_G", "TON", "CONCAT", "LEN", "Twice", "Acc", "Pt", "Color", "g", "K", "q", "a[0]",
         "p.x", "f.total", "x.3", "é", "\x00", "\t", "\n", "{native}"]

TOKEN = re.compile(r"\(\*|\*\)|//|:=|=>|\.\.|<=|>=|<>|\*\*|'[^']*'|[A-Za-z_][A-Za-z0-9_]*|[0-9][0-9_.#A-Fa-f]*|\S")


def mutate(text: str, rng: random.Random) -> str:
    for _ in range(rng.randint(1, 3)):
        tokens = [m.span() for m in TOKEN.finditer(text)]
        if not tokens:
            return text + rng.choice(VOCAB)
        a, b = rng.choice(tokens)
        op = rng.randrange(10)
        if op == 0:                                       # delete a character
            i = rng.randrange(len(text))
            text = text[:i] + text[i + 1:]
        elif op == 1:                                     # delete a token
            text = text[:a] + text[b:]
        elif op == 2:                                     # duplicate a token
            text = text[:b] + " " + text[a:b] + text[b:]
        elif op == 3:                                     # insert a vocabulary token
            text = text[:a] + rng.choice(VOCAB) + " " + text[a:]
        elif op == 4:                                     # replace a token
            text = text[:a] + rng.choice(VOCAB) + text[b:]
        elif op == 5:                                     # swap with the next token
            later = [t for t in tokens if t[0] >= b]
            if later:
                c, d = later[0]
                text = text[:a] + text[c:d] + text[b:c] + text[a:b] + text[d:]
        elif op == 6:                                     # truncate
            text = text[:rng.randrange(len(text))]
        elif op == 7:                                     # duplicate or drop a line
            lines = text.splitlines(keepends=True)
            i = rng.randrange(len(lines))
            lines.insert(i, lines[i]) if rng.random() < 0.5 else lines.pop(i)
            text = "".join(lines)
        elif op == 8:                                     # swap an identifier for another one
            names = [text[s:e] for s, e in tokens if re.fullmatch(r"[A-Za-z_]\w*", text[s:e])]
            if names:
                text = text[:a] + rng.choice(names) + text[b:]
        else:                                             # an extreme number
            text = text[:a] + rng.choice(["0", "-1", "32768", "2147483648", "18446744073709551616",
                                          "16#FFFF_FFFF", "1.0e40", "0.0"]) + text[b:]
    return text


def make_mutants(count: int, seed: int) -> list[str]:
    rng = random.Random(seed)
    return [mutate(rng.choice(SEEDS), rng) for _ in range(count)]


class _Hang(BaseException):
    pass


def _alarm(signum, frame):
    raise _Hang()


def run_guarded(argv, seconds: int = 10):
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(seconds)
    try:
        return cli(argv)
    except _Hang:
        return 98, "", "hang (watchdog)"
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


@pytest.fixture(scope="module")
def fuzz_results():
    results = []
    for i, text in enumerate(make_mutants(260, seed=61131)):
        path = write_st(text, f"mutant_{i}.st")
        argv = ["run", path, "--cycles", "3", "--no-cache"] if i % 4 else ["check", path]
        rc, out, err = run_guarded(argv)
        results.append((text, argv[0], rc, err))
    return results


def _report(bad) -> str:
    text, cmd, rc, err = bad[0]
    return f"{len(bad)} mutant(s) failed; first ({cmd}, rc={rc}):\n{text}\n--- stderr ---\n{err[-3000:]}"


def test_mutants_never_print_a_traceback(fuzz_results):
    bad = [r for r in fuzz_results if "Traceback" in r[3] or r[2] not in (0, 1, 2, 3)]
    assert not bad, _report(bad)


def test_mutants_never_hit_an_internal_error(fuzz_results):
    """A Python exception inside generated code is an stvm bug even when reported as a fault."""
    bad = [r for r in fuzz_results if "internal error" in r[3]]
    assert not bad, _report(bad)


def test_most_mutants_are_diagnosed_not_run(fuzz_results):
    codes = [r[2] for r in fuzz_results]
    assert codes.count(1) > len(codes) // 3          # the fuzzer does produce bad programs


def test_loop_program_mutants_check_cleanly():
    rng = random.Random(7)
    for i in range(40):
        path = write_st(mutate(LOOP_SEED, rng), f"loop_mutant_{i}.st")
        rc, out, err = run_guarded(["check", path])
        assert rc in (0, 1) and "Traceback" not in err, err


@pytest.mark.parametrize("text", ["", "\x00", "(*", "'", "PROGRAM", "PROGRAM Main", "END_PROGRAM",
                                  "\ufeff", "\r\n\r\n", "PROGRAM Main\rVAR x : INT; END_VAR\rEND_PROGRAM",
                                  "PROGRAM Main VAR x : ARRAY[1..2] OF ARRAY[1..2] OF INT; END_VAR END_PROGRAM",
                                  "PROGRAM Main VAR x : STRING[1+1]; END_VAR x := 'abc'; END_PROGRAM",
                                  "PROGRAM Main VAR x : REF_TO INT; y : INT; END_VAR y := x^; END_PROGRAM",
                                  "PROGRAM Main VAR x AT %IX0.0 : BOOL; END_VAR x := TRUE; END_PROGRAM",
                                  "FUNCTION F : INT F := F(); END_FUNCTION PROGRAM Main VAR x : INT; END_VAR "
                                  "x := F(); END_PROGRAM"])
def test_odd_files(text):
    path = write_st(text, "odd.st")
    for argv in (["check", path], ["run", path, "--cycles", "2", "--no-cache"]):
        rc, out, err = run_guarded(argv)
        assert rc in (0, 1, 2, 3) and "Traceback" not in err, err


ODD_VALUES = ["", "'", "''", "$", "T#", "16#", "1e", "--", "INT#", "Color#", "(1)", "[1, 2]", "(a := 1)",
              "1 + 2", "x", "TRUE TRUE", "\x00", "é", "1e999", "-0", "T#99999999999999999999d", "16#FFFF_FFFF_FFFF_FFFF_F"]


@pytest.mark.parametrize("value", ODD_VALUES, ids=[f"v{i}" for i in range(len(ODD_VALUES))])
def test_odd_set_and_print_arguments(value):
    path = write_st("TYPE Color : (Red); END_TYPE\nPROGRAM Main\nVAR i : INT; s : STRING; r : REAL; t : TIME; "
                    "c : Color; b : BOOL; a : ARRAY[1..2] OF INT; END_VAR\nEND_PROGRAM\n", "odd_set.st")
    for var in ("Main.i", "Main.s", "Main.r", "Main.c", "Main.a"):
        rc, out, err = run_guarded(["run", path, "--cycles", "0", "--set", f"{var}={value}"])   # cached load
        assert rc in (0, 2) and "Traceback" not in err, (var, err)
    rc, out, err = run_guarded(["run", path, "--cycles", "0", "--print", value or "''"])
    assert rc in (0, 2) and "Traceback" not in err, err


def test_set_real_to_a_huge_integer_is_a_usage_error():
    path = write_st("PROGRAM Main\nVAR r : REAL; l : LREAL; END_VAR\nEND_PROGRAM\n", "huge_set.st")
    for var in ("Main.r", "Main.l"):
        rc, out, err = run_guarded(["run", path, "--cycles", "1", "--no-cache", "--set", f"{var}={'9' * 400}"])
        assert rc in (0, 2) and "Traceback" not in err, err


LONG_VALID = {   # valid ST that once broke Python's compile limits: must run
    "sum_of_80_terms": ("y := " + " + ".join(["x"] * 80) + ";", 80),
    "sum_of_200_terms": ("y := " + " + ".join(["x"] * 200) + ";", 200),
    "parens_100_deep": ("y := " + "(" * 100 + "x" + " + 1)" * 100 + ";", 101),
    "for_nested_15": ("FOR i := 1 TO 1 DO " * 15 + "y := y + 1;" + " END_FOR;" * 15, 1),
    "if_nested_40": ("IF x > 0 THEN " * 40 + "y := 7;" + " END_IF;" * 40, 7),
}


@pytest.mark.parametrize("name", sorted(LONG_VALID))
def test_long_and_deep_valid_code_runs(name):
    body, expected = LONG_VALID[name]
    path = write_st(f"PROGRAM Main VAR x : DINT := 1; y : DINT; i : DINT; END_VAR {body} END_PROGRAM", f"long_{name}.st")
    rc, out, err = run_guarded(["run", path, "--cycles", "1", "--no-cache", "--print", "Main.y"])
    assert (rc, out) == (0, f"Main.y = {expected}\n"), err[-500:]


BEYOND_LIMITS = {  # nesting beyond what stvm compiles: a diagnostic, never a traceback
    "if_nested_100": "IF x > 0 THEN " * 100 + "y := 1;" + " END_IF;" * 100,
    "for_nested_20": "FOR i := 1 TO 1 DO " * 20 + "y := 1;" + " END_FOR;" * 20,
    "sum_of_2000_terms": "y := " + " + ".join(["x"] * 2000) + ";",
    "not_chain_3000": "b := " + "NOT " * 3000 + "TRUE;",
    "minus_chain_3000": "y := " + "-" * 3000 + "1;",
}


@pytest.mark.parametrize("name", sorted(BEYOND_LIMITS))
def test_code_beyond_limits_runs_or_is_diagnosed(name):
    path = write_st(f"PROGRAM Main VAR x : DINT := 1; y : DINT; i : DINT; b : BOOL; END_VAR "
                    f"{BEYOND_LIMITS[name]} END_PROGRAM", f"deep_{name}.st")
    for argv in (["check", path], ["run", path, "--cycles", "1", "--no-cache"]):
        rc, out, err = run_guarded(argv)
        assert "Traceback" not in err, err[-500:]
        assert rc == 0 or (rc == 1 and ": error:" in err), err[-500:]
