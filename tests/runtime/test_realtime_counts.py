"""`stvm run --realtime --stats` counts overruns, catch-up scans and scans over the period.

The programs are far from the boundary so the counts do not depend on the machine's load: the
slow one's scan takes well over 10 periods (a FOR loop against a 1 ms period), the fast one's a few
microseconds against a 200 ms period. Only counts are asserted, never times."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SLOW = """PROGRAM Main
VAR
  i : DINT;
  acc : DINT;
END_VAR
FOR i := 1 TO 40000 DO
  acc := acc + i MOD 7;
END_FOR
END_PROGRAM
"""

FAST = """PROGRAM Main
VAR
  n : DINT;
END_VAR
n := n + 1;
END_PROGRAM
"""

COUNTS = re.compile(r"overruns: (\d+)  catch-up scans: (\d+)  scans over the period: (\d+)")


def _run(tmp_path, text: str, *options: str) -> tuple[int, int, int, int]:
    path = tmp_path / "main.st"
    path.write_text(text)
    proc = subprocess.run([sys.executable, "-m", "stvm", "run", str(path), "--realtime", "--stats",
                           "--no-cache", *options], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert proc.returncode == 0, proc.stderr
    scans = int(re.search(r"scans: (\d+)", proc.stdout).group(1))
    found = COUNTS.search(proc.stdout)
    assert found, proc.stdout
    return scans, *map(int, found.groups())


def test_a_scan_ten_times_the_period_is_counted(tmp_path):
    # 40,000 iterations take tens of ms on any machine: every scan is over the 1 ms period
    scans, overruns, catch_up, long_scans = _run(tmp_path, SLOW, "--scan", "1ms", "--duration", "6ms")
    assert scans == 6
    assert long_scans == 6
    # one episode that never ends: the first scan already leaves the next start > 1 period late
    assert overruns == 1
    assert catch_up == 5


def test_two_scans_still_count_the_first(tmp_path):
    # the first scan used to start the schedule at its end: never late, and the second was a
    # spurious catch-up scan ("overruns: 0  catch-up scans: 1" whatever the program)
    scans, overruns, catch_up, long_scans = _run(tmp_path, SLOW, "--scan", "1ms", "--duration", "2ms")
    assert (scans, overruns, catch_up, long_scans) == (2, 1, 1, 2)


def test_a_scan_well_under_the_period_is_no_overrun(tmp_path):
    scans, overruns, catch_up, long_scans = _run(tmp_path, FAST, "--scan", "200ms", "--duration", "800ms")
    assert scans == 4
    assert (overruns, catch_up, long_scans) == (0, 0, 0)
