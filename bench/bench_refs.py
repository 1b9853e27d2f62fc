"""REF_TO dereference vs direct access (issue 11: a dereference costs at most 1.5× a direct access).

Run: python bench/bench_refs.py   (prints a table; no timed assertions anywhere)

Two generated PROGRAM bodies do the same 100-iteration FOR loop: one reads and writes a DINT and a
struct field directly, the other through a `REF_TO DINT` and a `REF_TO` struct (`r^ := r^ + i`,
`rp^.x := rp^.x + i`). The figure is the ratio of the two bodies' best times (the loop's own
cost is in both, as in real code). These loops hold `r^` in a Python local (the lowering option
`hold_derefs_in_loops`); the last row is a loop the option refuses (a call), where each
dereference is still a `.get()`/`.set()` call.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import stvm  # noqa: E402

TYPES = "TYPE Pt : STRUCT x : DINT; y : DINT; END_STRUCT; END_TYPE\n"
DIRECT = TYPES + """PROGRAM Main
VAR a : DINT; p : Pt; i : INT; END_VAR
FOR i := 1 TO 100 DO
    a := a + i;
    p.x := p.x + i;
END_FOR
END_PROGRAM
"""
THROUGH = TYPES + """PROGRAM Main
VAR a : DINT; p : Pt; i : INT; r : REF_TO DINT; rp : REF_TO Pt; END_VAR
r := REF(a);
rp := REF(p);
FOR i := 1 TO 100 DO
    r^ := r^ + i;
    rp^.x := rp^.x + i;
END_FOR
END_PROGRAM
"""
SCALAR_DIRECT = """PROGRAM Main
VAR a : DINT; i : INT; END_VAR
FOR i := 1 TO 100 DO a := a + i; END_FOR
END_PROGRAM
"""
SCALAR_THROUGH = """PROGRAM Main
VAR a : DINT; i : INT; r : REF_TO DINT; END_VAR
r := REF(a);
FOR i := 1 TO 100 DO r^ := r^ + i; END_FOR
END_PROGRAM
"""
STRUCT_DIRECT = TYPES + """PROGRAM Main
VAR p : Pt; i : INT; END_VAR
FOR i := 1 TO 100 DO p.x := p.x + i; END_FOR
END_PROGRAM
"""
STRUCT_THROUGH = TYPES + """PROGRAM Main
VAR p : Pt; i : INT; rp : REF_TO Pt; END_VAR
rp := REF(p);
FOR i := 1 TO 100 DO rp^.x := rp^.x + i; END_FOR
END_PROGRAM
"""

# an array element in the loop: held after a check before the loop that r^ is no element of arr
INDEXED_DIRECT = """PROGRAM Main
VAR a : DINT; i : INT; arr : ARRAY[1..100] OF DINT; END_VAR
FOR i := 1 TO 100 DO a := a + arr[i]; END_FOR
END_PROGRAM
"""
INDEXED_THROUGH = """PROGRAM Main
VAR a : DINT; i : INT; arr : ARRAY[1..100] OF DINT; r : REF_TO DINT; END_VAR
r := REF(a);
FOR i := 1 TO 100 DO r^ := r^ + arr[i]; END_FOR
END_PROGRAM
"""
# not held (`hold_derefs_in_loops` refuses a loop with a call: the callee could reach r^): every
# dereference is a `.get()`/`.set()` call
CALL_DIRECT = """PROGRAM Main
VAR a : DINT; i : INT; END_VAR
FOR i := 1 TO 100 DO a := a + ABS(i); END_FOR
END_PROGRAM
"""
CALL_THROUGH = """PROGRAM Main
VAR a : DINT; i : INT; r : REF_TO DINT; END_VAR
r := REF(a);
FOR i := 1 TO 100 DO r^ := r^ + ABS(i); END_FOR
END_PROGRAM
"""


def body_of(source: str, folder: Path, name: str):
    path = folder / f"{name}.st"
    path.write_text(source, encoding="utf-8")
    vm = stvm.load([path], use_cache=False).start(scan="1ms")
    return next(iter(vm.instances.values()))[1]


def best_of(fn, repeat: int, number: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - start) / number)
    return min(times)


def main() -> None:
    cases = [("DINT + struct field", DIRECT, THROUGH), ("DINT only", SCALAR_DIRECT, SCALAR_THROUGH),
             ("struct field only", STRUCT_DIRECT, STRUCT_THROUGH),
             ("DINT + array element", INDEXED_DIRECT, INDEXED_THROUGH),
             ("DINT + call (not held)", CALL_DIRECT, CALL_THROUGH)]
    print(f"{'100-iteration loop':24} {'direct µs':>10} {'REF_TO µs':>10} {'ratio':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for index, (label, direct_src, ref_src) in enumerate(cases):
            direct = body_of(direct_src, folder, f"direct{index}")
            through = body_of(ref_src, folder, f"through{index}")
            t_direct = best_of(direct, 15, 2000)
            t_ref = best_of(through, 15, 2000)
            print(f"{label:24} {t_direct * 1e6:10.2f} {t_ref * 1e6:10.2f} {t_ref / t_direct:6.2f}")


if __name__ == "__main__":
    main()
