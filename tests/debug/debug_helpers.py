"""Shared helpers for the debugger's tests (stvm/debug).

* `SMALL`: a small program with an FB, a FUNCTION, a FOR loop and a division, written once.
* `line_of(file, snippet)`: the ST line holding `snippet`, so tests of the thesis sources never
  hard-code line numbers that an erratum could move.
* `thesis_build()`: the debug build of the thesis project, loaded once per session (a build is
  never mutated: every engine starts a fresh VM from it).
"""

from __future__ import annotations

import functools
from pathlib import Path

from core_helpers import write_st

ROOT = Path(__file__).resolve().parents[2]
ST_SRC = ROOT / "st_src"
THESIS_MAIN = ST_SRC / "PnP_Example.st"
MOVE_ABSOLUTE = ST_SRC / "CBT_MoveAbsolute.st"
PNP_SCENARIO = ST_SRC / "scenarios" / "pnp_demo.toml"

SMALL = """\
FUNCTION Twice : INT
VAR_INPUT
    x : INT;
END_VAR
VAR
    tmp : INT;
END_VAR
tmp := x * 2;
Twice := tmp;
END_FUNCTION

FUNCTION_BLOCK Counter
VAR_INPUT
    Enable : BOOL;
END_VAR
VAR_OUTPUT
    Count : INT;
END_VAR
VAR
    history : ARRAY[0..4] OF INT;
    last : Pair;
END_VAR
IF Enable THEN
    Count := Count + 1;
    history[Count MOD 5] := Twice(Count);
    last.a := Count;
END_IF;
END_FUNCTION_BLOCK

TYPE Pair :
STRUCT
    a : INT;
    b : REAL := 1.5;
END_STRUCT;
END_TYPE

PROGRAM Main
VAR
    c : Counter;
    run : BOOL := TRUE;
    total : DINT;
    i : INT;
    divisor : INT := 1;
    grid : ARRAY[1..2, 1..3] OF INT;
END_VAR
c(Enable := run);
total := total + c.Count;
FOR i := 1 TO 3 DO
    total := total + i;
END_FOR;
grid[2, 3] := i;
total := total / divisor;
END_PROGRAM
"""


def small_path() -> Path:
    return write_st(SMALL, "small.st")


def line_of(file: Path | str, snippet: str, occurrence: int = 1) -> int:
    """1-based number of the line of `file` (a path, or ST text) that starts with `snippet`
    (leading blanks ignored)."""
    text = Path(file).read_text(encoding="utf-8") if isinstance(file, Path) else file
    seen = 0
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith(snippet):
            seen += 1
            if seen == occurrence:
                return number
    raise AssertionError(f"{snippet!r} not found in {file}")


def small_line(snippet: str, occurrence: int = 1) -> int:
    return line_of(SMALL, snippet, occurrence)


@functools.lru_cache(maxsize=None)
def thesis_build():
    from stvm.debug.build import load_debug
    from stvm.project import project_settings
    return load_debug([str(THESIS_MAIN)], project_settings([str(THESIS_MAIN)]))   # the manifest's: sysmac


@functools.lru_cache(maxsize=None)
def small_build():
    from stvm.debug.build import load_debug
    return load_debug([str(small_path())])


def start_engine(build, stop_on_entry: bool = True, **kwargs):
    """A started engine on `build`, stopped at entry (the caller terminates it)."""
    from stvm.debug.engine import Engine
    engine = Engine(build, **kwargs)
    engine.start(stop_on_entry=stop_on_entry)
    if stop_on_entry:
        assert engine.wait_started(30) is not None
    return engine
