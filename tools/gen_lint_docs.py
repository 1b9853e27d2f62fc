"""Regenerate docs/lint.md from the lint rule registry (stvm/lint/rules).

    python tools/gen_lint_docs.py           # write docs/lint.md
    python tools/gen_lint_docs.py --check   # exit 1 if docs/lint.md is out of date

tests/lint/test_lint_docs.py runs the check, so a rule changed without its page fails CI.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from stvm.lint.report import docs_page  # noqa: E402
from tools.generated_page import write_or_check  # noqa: E402

PAGE = ROOT / "docs" / "lint.md"


def main(argv: list[str]) -> int:
    return write_or_check(PAGE, docs_page(), argv, "python tools/gen_lint_docs.py")


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
