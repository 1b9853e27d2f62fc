"""`python -m stvm.syntax.gen_tables [--check | --print]`: regenerate (or check) the parser
tables shipped as `stvm/syntax/st_tables.json` from the grammar stvm parses with (see
stvm/syntax/tables.py for the format and why it is reproducible)."""

from __future__ import annotations

import sys

from stvm.syntax.parser import grammar_text, parser_options
from stvm.syntax.tables import FILE, generate


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    text = generate(grammar_text(), parser_options())
    if "--print" in args:
        sys.stdout.write(text)
        return 0
    if "--check" in args:
        current = FILE.read_text(encoding="ascii") if FILE.exists() else ""
        if current != text:
            print(f"{FILE} is not what the generator writes: run `python -m stvm.syntax.gen_tables`", file=sys.stderr)
            return 1
        return 0
    if FILE.exists() and FILE.read_text(encoding="ascii") == text:
        print(f"unchanged: {FILE}")
        return 0
    FILE.write_text(text, encoding="ascii")
    print(f"wrote {FILE} ({len(text):,} bytes)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
