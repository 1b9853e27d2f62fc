"""LTIME, LDATE, LTIME_OF_DAY, LDATE_AND_TIME (IEC 61131-3 ed. 3): distinct 64-bit types of the
TIME family, their literals, arithmetic, implicit widening, conversions and printing."""

from __future__ import annotations

import pytest

from core_helpers import check_text, cli, run_st, write_st

SOURCE = """
PROGRAM Main
VAR lt : LTIME := LTIME#1h2m; t : TIME := T#5s; sum : LTIME; d : LDATE := LDATE#2024-02-29;
    dt : LDT := LDT#2024-02-29-12:30:00.5; tod : LTOD; ns : LINT; s : STRING; back : TIME;
    widened : LTIME := T#3s; ms : DINT; parsed : LTIME; later : LDT; span : LTIME; big : LTIME;
    scaled : LTIME; neg : LTIME; same : BOOL; d2 : LDATE; short : DT; END_VAR
sum := lt + t;                          (* TIME widens to LTIME; the result is long *)
tod := LDT_TO_LTOD(dt);
d2 := LDT_TO_LDATE(dt);
ns := LTIME_TO_LINT(LT#1ms);            (* the long forms count nanoseconds *)
ms := TIME_TO_DINT(T#1ms);              (* TIME counts milliseconds (time_unit_ns) *)
s := LTIME_TO_STRING(sum);
back := LTIME_TO_TIME(sum);
parsed := STRING_TO_LTIME('LTIME#2s');
later := dt + LT#1d;
span := later - dt;
big := LINT_TO_LTIME(9000000000000000000);
scaled := lt * 2;
neg := -lt;
same := lt = T#1h2m;                    (* compared within the family *)
short := LDT_TO_DT(later);
END_PROGRAM
"""


def test_long_times_run_and_print_as_long_literals():
    names = ["sum", "d", "dt", "tod", "d2", "ns", "ms", "s", "back", "widened", "parsed", "later", "span",
             "big", "scaled", "neg", "same", "short"]
    rc, out, err = cli(["run", write_st(SOURCE), "--cycles", "1", *[a for v in names for a in ("--print", f"Main.{v}")]])
    assert rc == 0, err
    assert out.splitlines() == [
        "Main.sum = LT#1h2m5s", "Main.d = LD#2024-02-29", "Main.dt = LDT#2024-02-29-12:30:00.5",
        "Main.tod = LTOD#12:30:00.5", "Main.d2 = LD#2024-02-29", "Main.ns = 1000000", "Main.ms = 1",
        "Main.s = 'LT#1h2m5s'", "Main.back = T#1h2m5s", "Main.widened = LT#3s", "Main.parsed = LT#2s",
        "Main.later = LDT#2024-03-01-12:30:00.5", "Main.span = LT#1d", "Main.big = LT#104166d16h",
        "Main.scaled = LT#2h4m", "Main.neg = LT#-1h2m", "Main.same = TRUE",
        "Main.short = DT#2024-03-01-12:30:00.5"]


@pytest.mark.parametrize("line, message", [
    ("t := lt;", "cannot assign LTIME to TIME; use LTIME_TO_TIME"),
    ("ton1(IN := TRUE, PT := lt);", "cannot assign LTIME to TIME; use LTIME_TO_TIME"),
    ("d := lt;", "cannot assign LTIME to LDATE"),
    ("t := LT#1s;", "cannot assign LTIME to TIME"),
    ("lt := lt + d;", "operator + cannot be applied to LTIME and LDATE"),
])
def test_narrowing_and_mixing_families_are_errors(line, message):
    rc, err = check_text(f"""PROGRAM Main
VAR lt : LTIME; t : TIME; d : LDATE; ton1 : TON; END_VAR
{line}
END_PROGRAM
""")
    assert rc == 1 and "case.st:3:" in err and message in err, err


def test_a_long_literal_cannot_initialise_the_short_type():
    rc, err = check_text("PROGRAM Main VAR t : TIME := LT#1s; END_VAR END_PROGRAM\n")
    assert rc == 1 and "initial value does not fit type TIME" in err, err


def test_set_and_api_accept_long_literals():
    values = run_st("PROGRAM Main VAR lt : LTIME; d : LDT; END_VAR END_PROGRAM\n",
                    sets={"Main.lt": 5_000_000_000}, prints=["Main.lt"], fmt=True)
    assert values == {"Main.lt": "LT#5s"}
