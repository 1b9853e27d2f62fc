"""Cost of conditional compilation (stvm/syntax/conditional.py) on the parse: a 10,000-line
program with an `{attribute …}` pragma every 10 lines and an `{IF}`/`{ELSE}`/`{END_IF}` every
50, parsed with the preprocessing and with it skipped (the text has no directive: `{` alone).

    nice python bench/bench_conditional.py
"""

from __future__ import annotations

import time

from stvm.syntax import conditional
from stvm.syntax.parser import parse_text


def source(lines: int = 10_000) -> str:
    out = ["PROGRAM Main", "VAR i : INT; x : INT; END_VAR"]
    for k in range(lines // 10):
        out.append("{attribute 'hide'}" if k % 5 else "{IF defined(FAST)}")
        out += [f"x := x + {k};", "i := i + 1;", "IF x > 100 THEN x := 0; END_IF;", "x := x * 2;"]
        out.append("{ELSE}" if k % 5 == 0 else "(* - *)")
        out += ["x := x - 1;", "i := i - 1;", "x := x + i;"]
        out.append("{END_IF}" if k % 5 == 0 else "(* - *)")
    out.append("END_PROGRAM")
    return "\n".join(out) + "\n"


def best(fn, repeat: int = 5) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    text = source()
    pre = best(lambda: conditional.preprocess(text, "b.st", ()))
    full = best(lambda: parse_text(text, "b.st"))
    no_directive = text.replace("{IF defined(FAST)}", "(* - *)").replace("{ELSE}", "(* - *)").replace("{END_IF}", "(* -- *)")
    plain = best(lambda: parse_text(no_directive, "b.st"))
    print(f"{len(text.splitlines())} lines: preprocess {pre * 1000:.1f} ms, parse with directives {full * 1000:.0f} ms, "
          f"parse without directives {plain * 1000:.0f} ms ({pre / full:.1%} of the parse)")


if __name__ == "__main__":
    main()
