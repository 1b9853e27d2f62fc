"""docs/robotlibs_kuka.md stays true (issue 31): every member of the seed STRUCTs the blocks take and
every ErrorID the library documents is in the table, with tests that exist and mention it, or refused
with a reason."""

from __future__ import annotations

from pathlib import Path

from robotlibs_helpers import REPO, check_seed_table
from test_kuka_props import KUKA_CODES

HERE = Path(__file__).resolve().parent
STRUCTS = {"APO": ["PTP_MODE", "CP_MODE", "CPTP", "CDIS", "CORI", "CVEL"], "COORDSYS": ["Tool", "Base", "IPO_MODE"],
           "E6AXIS": [f"A{i}" for i in range(1, 7)] + [f"E{i}" for i in range(1, 7)],
           "E6POS": list("XYZABCST") + [f"E{i}" for i in range(1, 7)], "FRAME": list("XYZABC")}
ITEMS = [f"{s}.{m}" for s, members in STRUCTS.items() for m in members] + [str(c) for c in KUKA_CODES if c < 10000]


def spellings(item: str) -> list[str]:
    struct, _, member = item.partition(".")
    if not member:
        return [item]
    if struct == "E6POS" and member in "XYZABC":
        return ["pos"]                                    # KukaBench.pos sets X, Y, Z, A, B, C
    if struct == "FRAME":
        return ["TOOL_DATA", "BASE_DATA"]
    if struct == "E6AXIS" and member.startswith("E") or struct == "E6POS" and member.startswith("E"):
        return [member, "element"]
    return [member]


def test_every_seed_item_is_produced_by_a_test_or_refused_with_a_reason():
    check_seed_table(REPO / "docs" / "robotlibs_kuka.md", ITEMS, sorted(HERE.glob("test_*.py")), spellings)
