"""Regenerate the table of docs/dialects.md from the dialect profiles (stvm/dialects.py).

    python tools/gen_dialect_docs.py           # rewrite the table in docs/dialects.md
    python tools/gen_dialect_docs.py --check   # exit 1 if the page's table is out of date

Only the table under "## The table" is generated; the prose around it is written by hand.
tests/semantics/test_dialect_profiles.py runs the check, so a row changed without the page fails.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from stvm.dialects import table_markdown  # noqa: E402
from tools.generated_page import write_or_check  # noqa: E402

PAGE = ROOT / "docs" / "dialects.md"
HEADING = "## The table\n\n"


def with_table(page: str) -> str:
    """`page` with the table under HEADING replaced by the generated one."""
    start = page.index(HEADING) + len(HEADING)
    end = page.index("\n## ", start)
    return page[:start] + table_markdown() + page[end:]


def main(argv: list[str]) -> int:
    return write_or_check(PAGE, with_table(PAGE.read_text(encoding="utf-8")), argv,
                          "python tools/gen_dialect_docs.py")

if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
