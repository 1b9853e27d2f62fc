"""docs/robotlibs_rockwell.md stays true (issue 31): every seed 2.3 code is in its table, each
implemented/substituted one names tests that exist in tests/rockwell and contain the code (or the
parametrized table holds it), each refused one gives a reason and is listed in the LoadPath header."""

from __future__ import annotations

import re
from pathlib import Path

from robotlibs_helpers import REPO
from test_rockwell_props import SEED_CODES

DOC = REPO / "docs" / "robotlibs_rockwell.md"
TESTS = Path(__file__).resolve().parent / "test_load_path.py"
HEADER = (REPO / "st_src" / "rockwell" / "raM_Robot_Opr_LoadPath.st").read_text(encoding="utf-8").split("*)")[0]


def table() -> dict[int, tuple[str, str, str]]:
    rows = {}
    for line in DOC.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0].isdigit():
            rows[int(cells[0])] = (cells[1], cells[2], cells[3])
    return rows


def test_every_seed_code_is_in_the_table():
    assert set(table()) == set(SEED_CODES)


def test_every_listed_code_is_produced_by_a_test_or_refused_with_a_reason():
    source = TESTS.read_text(encoding="utf-8")
    for code, (status, why, tests) in table().items():
        if status == "refused":
            assert why, f"{code}: refused without a reason"
            assert str(code) in HEADER, f"{code}: refused in the docs but not in the LoadPath header"
        else:
            assert status in ("implemented", "substituted"), code
            names = re.findall(r"test_\w+", tests)
            assert names, f"{code}: no test named"
            for name in names:
                assert f"def {name}(" in source, f"{code}: {name} does not exist"
            assert re.search(rf"\b{code}\b", source), f"{code}: no test in test_load_path.py produces it"
