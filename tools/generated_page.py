"""Write a generated docs page, or check that the committed page is up to date.

The docs generators (gen_error_docs.py, gen_lint_docs.py) share this, so both answer `--check`
the same way: exit 1 with the command to run when the committed page differs from the registry.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def write_or_check(page: Path, text: str, argv: list[str], command: str) -> int:
    """Write `text` to `page`, or with `--check` in argv compare it: 0 when equal, 1 (and why) if not."""
    name = page.relative_to(ROOT)
    if "--check" in argv:
        current = page.read_text(encoding="utf-8") if page.exists() else ""
        if current != text:
            print(f"{name} is out of date: run {command}", file=sys.stderr)
            return 1
        return 0
    page.write_text(text, encoding="utf-8")
    print(f"wrote {name} ({len(text.splitlines())} lines)")
    return 0
