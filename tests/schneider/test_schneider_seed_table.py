"""docs/robotlibs_schneider.md stays true (issue 31): every q_etDiagExt value of the seed and every
method it names is in the table, implemented/substituted with tests that exist and mention it, or
refused with a reason."""

from __future__ import annotations

from pathlib import Path

from robotlibs_helpers import REPO, check_seed_table
from schneider_harness import EXT

HERE = Path(__file__).resolve().parent
# seed values (ChangeCoordinateSystem2's table); NewConnectedPath (43) is the library's status, not the seed's
SEED_EXT = [name for name, value in EXT.items() if value != 43]
METHODS = ["MoveL", "MoveC", "MoveS", "MoveSync", "Execute", "SetCoordinateSystem"]


def spellings(item: str) -> list[str]:
    return {"MoveC": ["move_c", "Circle"], "Ok": ["OK", "Ok"], "Execute": ["execute"],
            "SetCoordinateSystem": ["set_cs"]}.get(item, [item])


def test_every_seed_item_is_produced_by_a_test_or_refused_with_a_reason():
    check_seed_table(REPO / "docs" / "robotlibs_schneider.md", SEED_EXT + METHODS,
                     sorted(HERE.glob("test_*.py")), spellings)
