"""The restored ST bodies in ``st_src/`` differ from the thesis listings only by ``st_src/ERRATA.md``.

For each POU printed in the thesis (Annex A1-A7: the seven ``CBT_*`` function blocks,
Annex B1: ``PnP_Example``) the test

1. extracts the printed listing from the seed text (the fenced code blocks between the
   ``A<n>.`` / ``B1.`` headings; a listing spans several fences, one per PDF page),
2. strips the printed line numbers (``12``, ``12.``, ``12:``) and joins the unnumbered
   lines the PDF wrapped onto the numbered line above them (one logical line each),
3. normalises whitespace (runs of blanks collapsed to one space, blank lines dropped),
4. applies the ERRATA rows of that listing (each ``printed`` text must occur exactly once
   in the logical line that holds the row's thesis line, and is replaced by ``restored``),
5. compares the result line by line with the body of the matching ``st_src/*.st`` file
   (the text between the last ``END_VAR`` and ``END_FUNCTION_BLOCK``/``END_PROGRAM``,
   normalised the same way) and fails with a unified diff.

Pure Python, no dependency on ``stvm``. The seed is looked up in ``$STVM_THESIS_SEED``,
then ``../shared/seeds/`` next to the repository, else the vendored copy of the annexes
(``tests/thesis/data/thesis_annexes.txt``).
"""

from __future__ import annotations

import difflib
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
ST_SRC = REPO / "st_src"
ERRATA_MD = ST_SRC / "ERRATA.md"
SEED_NAME = "002_b5190e8af93ee4b4.txt"

#: thesis listing heading -> (POU name, st_src file)
LISTINGS: dict[str, tuple[str, str]] = {
    "A1": ("CBT_Connect", "CBT_Connect.st"),
    "A2": ("CBT_MoveAbsolute", "CBT_MoveAbsolute.st"),
    "A3": ("CBT_MoveRelative", "CBT_MoveRelative.st"),
    "A4": ("CBT_MoveCircle", "CBT_MoveCircle.st"),
    "A5": ("CBT_ChangeBase", "CBT_ChangeBase.st"),
    "A6": ("CBT_ChangeTCP", "CBT_ChangeTCP.st"),
    "A7": ("CBT_ProgramControl", "CBT_ProgramControl.st"),
    "B1": ("PnP_Example", "PnP_Example.st"),
}

ANNEX_START = re.compile(r"^#\s+Annex A\b", re.IGNORECASE)
LISTING_HEADING = re.compile(r"^#{1,4}\s+(A[1-7]|B1)\.\s")
FENCE = re.compile(r"^```")
PRINTED_NUMBER = re.compile(r"^\s*(\d+)[.:]?(?:\s(.*))?$")


# --------------------------------------------------------------------------- seed


VENDORED_ANNEXES = Path(__file__).resolve().parent / "data" / "thesis_annexes.txt"
VENDORED_FIRST_LINE = 4122   # seed line of the vendored copy's third line (after its 2-line header)


def find_seed() -> Path | None:
    """Locate the thesis text (``$STVM_THESIS_SEED`` or ``../shared/seeds/<name>``)."""
    candidates = []
    if os.environ.get("STVM_THESIS_SEED"):
        candidates.append(Path(os.environ["STVM_THESIS_SEED"]))
    candidates += [REPO.parent / "shared" / "seeds" / SEED_NAME, REPO / "shared" / "seeds" / SEED_NAME]
    return next((p for p in candidates if p.is_file()), None)


def seed_text() -> str:
    """The thesis text, or the vendored copy of its annexes padded so that line numbers match
    the seed (CI clones may not have ../shared next to them)."""
    seed = find_seed()
    if seed is not None:
        return seed.read_text(encoding="utf-8")
    annex_lines = VENDORED_ANNEXES.read_text(encoding="utf-8").split("\n")[2:]
    return "\n" * (VENDORED_FIRST_LINE - 1) + "\n".join(annex_lines)


@dataclass
class PrintedLine:
    """One logical line of a printed listing."""

    seed_lines: list[int]  # 1-based lines of the seed file it was printed on
    text: str  # printed text, line number stripped, wrapped parts joined with one space


class Listings(dict):
    """Heading id -> logical lines; short repr keeps pytest failure reports readable."""

    def __repr__(self) -> str:
        return f"<printed listings {', '.join(f'{k}:{len(v)} lines' for k, v in self.items())}>"


class ErrataTable(list):
    """Parsed ERRATA.md rows; short repr keeps pytest failure reports readable."""

    def __repr__(self) -> str:
        return f"<{len(self)} errata rows>"


def extract_printed_listings(seed_text: str) -> Listings:
    """Printed code of Annex A1..A7 and B1, keyed by heading id, as logical lines."""
    listings = Listings()
    current: str | None = None
    in_annex = in_fence = False
    for lineno, raw in enumerate(seed_text.split("\n"), start=1):
        if not in_annex:
            in_annex = bool(ANNEX_START.match(raw))
            continue
        if FENCE.match(raw):
            in_fence = not in_fence
            continue
        if not in_fence:
            heading = LISTING_HEADING.match(raw)
            if heading:
                current = heading.group(1)
                listings[current] = []
            continue
        if current is None or not raw.strip():
            continue
        numbered = PRINTED_NUMBER.match(raw)
        if numbered:
            listings[current].append(PrintedLine([lineno], numbered.group(2) or ""))
        elif listings[current]:  # PDF wrap: continuation of the numbered line above
            last = listings[current][-1]
            last.seed_lines.append(lineno)
            last.text += " " + raw.strip()
        else:
            raise AssertionError(f"seed line {lineno}: unnumbered text before the first numbered line")
    return listings


def normalise_line(text: str) -> str:
    """Collapse every run of whitespace to one blank and trim the ends."""
    return " ".join(text.split())


def normalise_lines(lines: list[str]) -> list[str]:
    """Normalised non-empty lines."""
    return [n for n in (normalise_line(x) for x in lines) if n]


# --------------------------------------------------------------------------- errata


@dataclass
class Erratum:
    id: str
    thesis_line: int
    printed: str
    restored: str
    reason: str
    applied: int = field(default=0, compare=False)


def _split_row(row: str) -> list[str]:
    """Cells of a markdown table row; ``\\|`` is a literal ``|`` inside a cell."""
    body = row.strip()
    if body.startswith("|"):
        body = body[1:]
    if body.endswith("|") and not body.endswith("\\|"):
        body = body[:-1]
    return [c.replace("\\|", "|").strip() for c in re.split(r"(?<!\\)\|", body)]


def _code_cell(cell: str, where: str) -> str:
    """Text of a cell written as one code span; an empty cell is the empty string."""
    if cell == "":
        return ""
    if len(cell) < 2 or not (cell.startswith("`") and cell.endswith("`")) or "`" in cell[1:-1]:
        raise AssertionError(f"{where}: expected one `code span`, got {cell!r}")
    return cell[1:-1]


def parse_errata(md_text: str) -> ErrataTable:
    """Rows ``| id | thesis line | printed | restored | reason |`` of the errata table(s)."""
    errata = ErrataTable()
    for n, row in enumerate(md_text.splitlines(), start=1):
        if not row.lstrip().startswith("|"):
            continue
        cells = _split_row(row)
        if len(cells) != 5 or not re.fullmatch(r"E\d+", cells[0]):
            continue  # header, separator or another table
        where = f"ERRATA.md line {n} ({cells[0]})"
        if not cells[1].isdigit():
            raise AssertionError(f"{where}: thesis line must be one integer, got {cells[1]!r}")
        errata.append(
            Erratum(cells[0], int(cells[1]), _code_cell(cells[2], where), _code_cell(cells[3], where), cells[4])
        )
    return errata


def apply_errata(listing: list[PrintedLine], errata: list[Erratum]) -> list[str]:
    """Normalised listing lines with the errata applied (in table order, line by line)."""
    texts = [normalise_line(pl.text) for pl in listing]
    owner = {s: i for i, pl in enumerate(listing) for s in pl.seed_lines}
    for e in errata:
        i = owner[e.thesis_line]
        printed = normalise_line(e.printed)
        count = texts[i].count(printed)
        if count != 1:
            raise AssertionError(
                f"{e.id} (thesis line {e.thesis_line}): printed text {printed!r} occurs {count} times in\n"
                f"    {texts[i]!r}"
            )
        texts[i] = texts[i].replace(printed, normalise_line(e.restored))
        e.applied += 1
    return [t for t in texts if t]


# --------------------------------------------------------------------------- st_src


END_VAR = re.compile(r"\bEND_VAR\b", re.IGNORECASE)
END_POU = re.compile(r"\b(END_FUNCTION_BLOCK|END_PROGRAM)\b", re.IGNORECASE)


def st_body(st_text: str) -> str:
    """Text between the last ``END_VAR`` and the following ``END_FUNCTION_BLOCK``/``END_PROGRAM``."""
    last_end_var = None
    for last_end_var in END_VAR.finditer(st_text):
        pass
    if last_end_var is None:
        raise AssertionError("no END_VAR in the file")
    end = END_POU.search(st_text, last_end_var.end())
    if end is None:
        raise AssertionError("no END_FUNCTION_BLOCK / END_PROGRAM after the last END_VAR")
    return st_text[last_end_var.end() : end.start()]


def diff_report(expected: list[str], actual: list[str], name: str) -> str:
    """Readable unified diff, printed+errata on the left, st_src on the right."""
    return "\n".join(
        difflib.unified_diff(
            expected, actual, fromfile=f"thesis listing of {name} + ERRATA.md", tofile=f"st_src/{name}.st body", lineterm="", n=2
        )
    )


# --------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def listings() -> Listings:
    return extract_printed_listings(seed_text())


@pytest.fixture(scope="module")
def errata() -> ErrataTable:
    return parse_errata(ERRATA_MD.read_text(encoding="utf-8"))


def errata_of(listing: list[PrintedLine], errata: list[Erratum]) -> list[Erratum]:
    lines = {s for pl in listing for s in pl.seed_lines}
    return [e for e in errata if e.thesis_line in lines]


# --------------------------------------------------------------------------- tests


def test_all_listings_extracted(listings):
    assert sorted(listings) == sorted(LISTINGS)
    for key, lines in listings.items():
        assert len(lines) > 100, f"listing {key} looks truncated ({len(lines)} lines)"


def test_errata_table_well_formed(listings, errata):
    assert errata, "no errata rows parsed from ERRATA.md"
    ids = [e.id for e in errata]
    assert len(ids) == len(set(ids)), "duplicate erratum ids"
    all_lines = {s: k for k, lst in listings.items() for pl in lst for s in pl.seed_lines}
    stray = [f"{e.id}: line {e.thesis_line}" for e in errata if e.thesis_line not in all_lines]
    assert not stray, "errata outside the printed listings: " + ", ".join(stray)
    same = [e.id for e in errata if normalise_line(e.printed) == normalise_line(e.restored)]
    assert not same, f"errata that change nothing: {same}"
    assert all(e.reason for e in errata), "every erratum needs a reason"


@pytest.mark.parametrize("key", sorted(LISTINGS))
def test_body_is_printed_text_plus_errata(key, listings, errata):
    name, filename = LISTINGS[key]
    mine = errata_of(listings[key], errata)
    expected = apply_errata(listings[key], mine)
    actual = normalise_lines(st_body((ST_SRC / filename).read_text(encoding="utf-8")).split("\n"))
    assert expected == actual, (
        f"st_src/{filename} differs from the printed listing {key} beyond ERRATA.md:\n"
        + diff_report(expected, actual, name)
    )
    unused = [e.id for e in mine if e.applied != 1]
    assert not unused, f"errata not applied exactly once: {unused}"
