"""LTON, LTOF, LTP (IEC 61131-3 ed. 3, table 46): TON, TOF and TP with LTIME PT and ET."""

from __future__ import annotations

import pytest

from core_helpers import check_text, cli, write_st

SOURCE = """
PROGRAM Main
VAR
    on_delay : LTON; off_delay : LTOF; pulse : LTP;
    start : BOOL := TRUE;
    q_on, q_off, q_pulse : BOOL;
    et_on, et_off, et_pulse : LTIME;
    scans : INT;
END_VAR
scans := scans + 1;
IF scans = 4 THEN start := FALSE; END_IF;
on_delay(IN := start, PT := LT#25ms, Q => q_on, ET => et_on);
off_delay(IN := start, PT := T#15ms, Q => q_off, ET => et_off);   (* a TIME widens to LTIME *)
pulse(IN := start, PT := LTIME#20ms, Q => q_pulse, ET => et_pulse);
END_PROGRAM
"""


@pytest.mark.parametrize("cycles, expected", [
    (1, ["FALSE", "LT#0s", "TRUE", "LT#0s", "TRUE", "LT#0s"]),
    (3, ["FALSE", "LT#20ms", "TRUE", "LT#0s", "FALSE", "LT#20ms"]),  # the pulse ended at 20 ms
    (4, ["FALSE", "LT#0s", "TRUE", "LT#0s", "FALSE", "LT#0s"]),      # IN fell at 30 ms
    (6, ["FALSE", "LT#0s", "FALSE", "LT#15ms", "FALSE", "LT#0s"]),   # TOF ran out 15 ms later
])
def test_long_timers_follow_the_vm_clock(cycles, expected):
    names = ["q_on", "et_on", "q_off", "et_off", "q_pulse", "et_pulse"]
    rc, out, err = cli(["run", write_st(SOURCE), "--scan", "10ms", "--cycles", str(cycles),
                        *[arg for v in names for arg in ("--print", f"Main.{v}")]])
    assert rc == 0, err
    assert [line.split(" = ")[1] for line in out.splitlines()] == expected


def test_lton_reaches_its_preset():
    rc, out, err = cli(["run", write_st("""PROGRAM Main
VAR t : LTON; END_VAR
t(IN := TRUE, PT := LT#30ms);
END_PROGRAM
"""), "--scan", "10ms", "--cycles", "5", "--print", "Main.t.Q", "--print", "Main.t.ET"])
    assert rc == 0, err
    assert out.splitlines() == ["Main.t.Q = TRUE", "Main.t.ET = LT#30ms"]


@pytest.mark.parametrize("line, message", [
    ("t(IN := TRUE, PT := LT#1s); short := t.ET;", "cannot assign LTIME to TIME; use LTIME_TO_TIME"),
    ("t(IN := TRUE, PT := 5);", "error:"),
    ("t(IN := TRUE, PT := LT#1s, ET => short);", "output ET is LTIME; cannot bind it to TIME"),
])
def test_long_timer_type_errors(line, message):
    rc, err = check_text(f"""PROGRAM Main
VAR t : LTON; short : TIME; END_VAR
{line}
END_PROGRAM
""")
    assert rc == 1 and ":3:" in err and message in err, err
