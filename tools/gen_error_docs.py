"""Regenerate docs/error_codes.md from the error-code registry (stvm/diagnostics/codes.py).

    python tools/gen_error_docs.py           # write docs/error_codes.md
    python tools/gen_error_docs.py --check   # exit 1 if docs/error_codes.md is out of date

tests/diagnostics/test_error_codes.py runs the check, so a code changed without its page fails CI.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from stvm.diagnostics.codes import docs_page  # noqa: E402
from tools.generated_page import write_or_check  # noqa: E402

PAGE = ROOT / "docs" / "error_codes.md"


def main(argv: list[str]) -> int:
    return write_or_check(PAGE, docs_page(), argv, "python tools/gen_error_docs.py")


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
