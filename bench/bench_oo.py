"""Method and interface calls vs a plain FB call (issue 11: a method call costs at most 1.5× and an
interface call at most 2× a plain FB call).

Run: python bench/bench_oo.py   (prints a table; no timed assertions anywhere)

Three PROGRAM bodies do the same 100-iteration FOR loop, each passing `i` in and reading a DINT
result back: a plain FB call (`f(a := i); s := s + f.q;`), a METHOD call on the instance
(`s := s + f.Calc(i);`) and the same METHOD through an interface variable (`s := s + itf.Calc(i);`).
The figure is the ratio of the bodies' best times (the loop's own cost is in all of them).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import stvm  # noqa: E402
from bench_core import best_of  # noqa: E402

DECLS = """
INTERFACE I_Calc
METHOD Calc : DINT
VAR_INPUT a : DINT; END_VAR
END_METHOD
END_INTERFACE

FUNCTION_BLOCK FB_Plain
VAR_INPUT a : DINT; END_VAR
VAR_OUTPUT q : DINT; END_VAR
q := a * 2;
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Oo IMPLEMENTS I_Calc
METHOD Calc : DINT
VAR_INPUT a : DINT; END_VAR
Calc := a * 2;
END_METHOD
END_FUNCTION_BLOCK
"""
PLAIN = DECLS + """PROGRAM Main
VAR f : FB_Plain; s : DINT; i : DINT; END_VAR
s := 0;
FOR i := 1 TO 100 DO f(a := i); s := s + f.q; END_FOR
END_PROGRAM
"""
METHOD = DECLS + """PROGRAM Main
VAR f : FB_Oo; s : DINT; i : DINT; END_VAR
s := 0;
FOR i := 1 TO 100 DO s := s + f.Calc(i); END_FOR
END_PROGRAM
"""
INTERFACE = DECLS + """PROGRAM Main
VAR f : FB_Oo; itf : I_Calc; s : DINT; i : DINT; END_VAR
itf := f;
s := 0;
FOR i := 1 TO 100 DO s := s + itf.Calc(i); END_FOR
END_PROGRAM
"""


def body_of(source: str, folder: Path, name: str):
    path = folder / f"{name}.st"
    path.write_text(source, encoding="utf-8")
    vm = stvm.load([path], use_cache=False).start(scan="1ms")
    vm.run(cycles=1)
    assert vm["Main.s"] == 10100, vm["Main.s"]   # the three bodies compute the same
    return next(iter(vm.instances.values()))[1]


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        bodies = [(label, body_of(src, folder, label.split()[0])) for label, src in
                  (("plain FB call", PLAIN), ("method call", METHOD), ("interface call", INTERFACE))]
        times = {}
        for _ in range(3):   # interleaved: the machine is shared
            for label, body in bodies:
                t = best_of(body, 7, 1000)
                times[label] = min(times.get(label, t), t)
        base = times["plain FB call"]
        print(f"{'100 calls in a FOR loop':24} {'µs':>8} {'vs FB call':>10}")
        for label, _ in bodies:
            print(f"{label:24} {times[label] * 1e6:8.2f} {times[label] / base:10.2f}")


if __name__ == "__main__":
    main()
