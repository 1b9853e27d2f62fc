"""Scenario events fire for the scan they name (stvm/scenario.py `ScenarioDriver`), whether the
driver checks them every scan or skips the scans where none is due (`_plan`): `scan = N` is set
before scan N runs, `time = T` before the first scan starting at or after T, `when = FLAG` before
the scan after the one that left FLAG TRUE."""

from __future__ import annotations

import stvm
from stvm.scenario import ScenarioDriver, load_scenario

PROGRAM = """
PROGRAM Main
VAR n : INT; flag : BOOL; a : INT; b : INT; c : INT; d : INT; END_VAR
n := n + 1;
flag := n = 7;
END_PROGRAM
"""

SCENARIO = """
[[at]]
scan = 3
set = { "Main.a" = 1 }

[[at]]
time = "T#45ms"
set = { "Main.b" = 1 }

[[at]]
when = "Main.flag"
set = { "Main.c" = 1 }

[[at]]
scan = 12
set = { "Main.d" = 1 }
"""


def _first_scan_with(tmp_path, replan_every_scan: bool) -> dict[str, int]:
    src = tmp_path / "main.st"
    src.write_text(PROGRAM, encoding="utf-8")
    toml = tmp_path / "s.toml"
    toml.write_text(SCENARIO, encoding="utf-8")
    vm = stvm.load([str(src)]).start(scan="10ms")
    driver = ScenarioDriver(load_scenario(toml), vm)
    vm.on_scan_end.append(driver.after_scan)
    driver.apply_initial()
    seen: dict[str, int] = {}
    for _ in range(20):
        if replan_every_scan:
            driver._watching = True   # as if every scan might have something due
        n = vm.get("Main.n")          # scans run so far: the number of the next scan
        for name in "abcd":
            if vm.get(f"Main.{name}") and name not in seen:
                seen[name] = n
        vm.scan()
    return seen


def test_events_fire_for_the_scan_they_name(tmp_path):
    seen = _first_scan_with(tmp_path, False)
    # scan 3; T#45ms: scans start every 10 ms, the first at or after 45 ms is scan 5; flag is
    # TRUE after scan 6 (n = 7): set for scan 7; scan 12
    assert seen == {"a": 3, "b": 5, "c": 7, "d": 12}
    assert seen == _first_scan_with(tmp_path, True)
