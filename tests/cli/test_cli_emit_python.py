"""`stvm check --emit-python` (stvm/lower/listing.py): the generated Python of each POU with the
ST file:line of every generated line, through the driver's stages."""

from __future__ import annotations

import re
from pathlib import Path

from core_helpers import cli, write_st

from stvm.project import Options, check_stage, compile_stage, parse_stage, resolve

ROOT = Path(__file__).resolve().parents[2]

SOURCE = """\
FUNCTION Twice : INT
VAR_INPUT x : INT; END_VAR
Twice := x * 2;
END_FUNCTION

TYPE Pair :
STRUCT
    a : INT;
    b : REAL;
END_STRUCT
END_TYPE

FUNCTION_BLOCK Counter
VAR_INPUT Enable : BOOL; END_VAR
VAR_OUTPUT Count : INT; END_VAR
IF Enable THEN
    Count := Twice(Count) + 1;
END_IF;
END_FUNCTION_BLOCK

VAR_GLOBAL g : Pair; END_VAR

PROGRAM Main
VAR c : Counter; t : TON; END_VAR
c(Enable := TRUE);
t(IN := c.Count > 3, PT := T#1s);
g.a := c.Count;
END_PROGRAM
"""

_ROW = re.compile(r"^\s*(\d+)  (\S*)\s*\| ?(.*)$")


def _rows(listing: str) -> list[tuple[int, str, str]]:
    """(generated line, ST file:line or '', code) of every listed line."""
    rows = []
    for line in listing.splitlines():
        if line and not line.startswith("#"):
            match = _ROW.match(line)
            assert match, line
            rows.append((int(match.group(1)), match.group(2), match.group(3)))
    return rows


def _line(snippet: str) -> int:
    return next(i for i, line in enumerate(SOURCE.splitlines(), 1) if snippet in line)


def _lowered(path: Path):
    checked = check_stage(parse_stage(resolve([str(path)], Options())))
    return compile_stage(checked).lowered


def test_every_pou_of_the_project_with_its_st_lines(tmp_path):
    path = write_st(SOURCE, "main.st", tmp_path)
    rc, out, err = cli(["check", path, "--emit-python"])
    assert rc == 0, err
    titles = [line for line in out.splitlines() if line.startswith("# ")]
    assert {title.split(" (")[0].split(" ->")[0] for title in titles} == {
        "# FUNCTION Twice", "# TYPE Pair", "# FUNCTION_BLOCK Counter", "# VAR_GLOBAL", "# PROGRAM Main"}
    assert "TON" not in "".join(titles)          # the stdlib only when asked for (--pou)
    lowered = _lowered(path)
    source = lowered.source.splitlines()
    rows = _rows(out)
    for number, where, code in rows:              # the generated line as the VM runs it
        assert code == source[number - 1].rstrip()
        span = lowered.line_map.span_at(number)
        assert where == (f"{span.file}:{span.line}" if span is not None else "")
    listed_st_lines = {int(where.rsplit(":", 1)[1]) for _, where, _ in rows if where}
    statements = ["Twice := x * 2;", "IF Enable THEN", "Count := Twice(Count) + 1;", "c(Enable := TRUE);",
                  "t(IN := c.Count > 3, PT := T#1s);", "g.a := c.Count;"]
    assert {_line(s) for s in statements} <= listed_st_lines
    # the FB's addition wraps to INT on the generated line of its ST line
    assert any(where.endswith(f":{_line('Count := Twice(Count) + 1;')}") and "_twice(" in code and "65535" in code
               for _, where, code in rows)


def test_pou_selects_units_of_the_stdlib_too(tmp_path):
    path = write_st(SOURCE, "main.st", tmp_path)
    rc, out, err = cli(["check", path, "--pou", "ton", "--pou", "Main"])
    assert rc == 0, err
    titles = [line for line in out.splitlines() if line.startswith("# ")]
    assert len(titles) == 2    # in the generated module's order
    assert any(title.startswith("# FUNCTION_BLOCK TON (<stdlib>/") for title in titles)
    assert any(title.startswith("# PROGRAM Main") for title in titles)
    rc, out, err = cli(["check", path, "--pou", "NoSuchBlock"])
    assert rc == 2 and "no such POU" in err and out == ""


def test_errors_print_diagnostics_and_no_listing(tmp_path):
    path = write_st("PROGRAM Main\nVAR x : INT; END_VAR\nx := y;\nEND_PROGRAM\n", "bad.st", tmp_path)
    rc, out, err = cli(["check", path, "--emit-python"])
    assert rc == 1 and out == ""
    assert re.search(r"bad\.st:3:\d+: error", err) and "Traceback" not in err


def test_a_project_with_a_manifest_lists_every_file(tmp_path):
    """Two files of the thesis project: the manifest is honoured (as `stvm check` does)."""
    files = [ROOT / "st_src" / "CBT_Connect.st", ROOT / "st_src" / "CBT_MoveAbsolute.st"]
    rc, out, err = cli(["check", *files, "--emit-python"])
    assert rc == 0, err
    titles = "\n".join(line for line in out.splitlines() if line.startswith("# "))
    for name in ("CBT_Connect", "CBT_MoveAbsolute"):   # (declared in a namespace: `Lib\\CBT_Connect`)
        assert re.search(rf"^# FUNCTION_BLOCK \S*\b{name} \(", titles, re.MULTILINE), titles
    assert any(where.startswith(("st_src/CBT_Connect.st:", str(files[0]) + ":")) for _, where, _ in _rows(out))
