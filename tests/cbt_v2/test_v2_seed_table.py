"""docs/robotlibs_cbt_v2.md stays true (issue 31): every ErrorID of the thesis and V2 is in the table,
produced by a named test or refused with a reason."""

from __future__ import annotations

from pathlib import Path

from robotlibs_helpers import REPO, V2_ERROR_IDS, check_seed_table

HERE = Path(__file__).resolve().parent


def spellings(item: str) -> list[str]:
    c = int(item[3:], 16)
    return [f"0x{c:x}", f"0x{c:X}", f"0x{c:02x}", f"0x{c:02X}", f"16#{c:02X}"]


def test_every_error_id_is_produced_by_a_test_or_refused_with_a_reason():
    check_seed_table(REPO / "docs" / "robotlibs_cbt_v2.md", [f"16#{c:02X}" for c in V2_ERROR_IDS],
                     sorted(HERE.glob("test_*.py")), spellings)
