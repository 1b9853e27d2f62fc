"""Diagnostics snapshots: tests/semantics/diagnostics/<case>.st next to <case>.stderr.

`stvm check <case>.st --dialect sysmac` (run in that folder, so paths are stable) must print exactly the
snapshot. `(* error … *)` comments state intent: every line carrying one must get at least one
error and no other line may. A mismatch writes `<case>.stderr.new` next to the snapshot;
`pytest --update-goldens` (or STVM_UPDATE_GOLDENS=1) rewrites the snapshots instead.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from core_helpers import cli

HERE = Path(__file__).resolve().parent / "diagnostics"
# snapshots of cases where stvm is known to be wrong (see tests/CORE_BUGS.md): strict xfail
KNOWN_BUGS = {
}
CASES = [pytest.param(path, id=path.stem,
                      marks=[pytest.mark.xfail(strict=True, reason=f"stvm bug: {KNOWN_BUGS[path.stem]}")]
                      if path.stem in KNOWN_BUGS else [])
         for path in sorted(HERE.glob("*.st"))]
ERROR_LINE = re.compile(r"^(?P<file>[^:\s][^:]*):(?P<line>\d+):(?P<col>\d+): (?P<kind>error|warning): (?P<msg>.+)$")


@pytest.mark.parametrize("case", CASES)
def test_diagnostics_snapshot(case: Path, update_goldens: bool, monkeypatch):
    monkeypatch.chdir(HERE)
    # the snapshots are of Sysmac code (STRING[n] counting the NUL, Omron's name rules)
    rc, out, err = cli(["check", case.name, "--dialect", "sysmac"])
    assert "Traceback" not in err
    assert out == ""
    golden = case.with_suffix(".stderr")
    new = case.with_suffix(".stderr.new")
    if update_goldens:
        golden.write_text(err, encoding="utf-8")
        new.unlink(missing_ok=True)
    else:
        assert golden.exists(), f"no snapshot {golden.name}; run pytest --update-goldens and review it"
        expected = golden.read_text(encoding="utf-8")
        if err != expected:
            new.write_text(err, encoding="utf-8")
        else:
            new.unlink(missing_ok=True)
        assert err == expected, f"stderr differs from {golden.name} (see {new.name})"

    errors = [m for m in map(ERROR_LINE.match, err.splitlines()) if m and m["kind"] == "error"]
    assert rc == (1 if errors else 0)
    if errors:
        assert err.rstrip().endswith(f"{len(errors)} error(s)")
    # every diagnostic names this file and is followed by the source line and a caret
    lines = err.splitlines()
    for i, line in enumerate(lines):
        m = ERROR_LINE.match(line)
        if m:
            assert m["file"] == case.name
            assert lines[i + 2].strip().startswith("^"), lines[i:i + 3]


@pytest.mark.parametrize("case", CASES)
def test_error_comments_state_intent(case: Path, monkeypatch):
    monkeypatch.chdir(HERE)
    rc, _, err = cli(["check", case.name, "--dialect", "sysmac"])
    text = case.read_text(encoding="utf-8").splitlines()
    intended = {i + 1 for i, line in enumerate(text) if "(* error" in line}
    reported = {int(m["line"]) for m in map(ERROR_LINE.match, err.splitlines()) if m and m["kind"] == "error"}
    # a syntax error stops the file: only its own line counts
    error_messages = [m["msg"] for m in map(ERROR_LINE.match, err.splitlines()) if m and m["kind"] == "error"]
    if any("syntax error" in msg or "end of file" in msg or "string literal" in msg for msg in error_messages):
        assert len(reported) == 1
        (line,) = reported
        assert line in intended or line - 1 in intended or line + 1 in intended
        return
    assert reported == intended, f"errors on lines {sorted(reported)}, comments on {sorted(intended)}"
    warned = {i + 1 for i, line in enumerate(text) if "(* warning" in line}
    warnings = {int(m["line"]) for m in map(ERROR_LINE.match, err.splitlines()) if m and m["kind"] == "warning"}
    assert warned <= warnings


def test_diagnostics_are_sorted_and_collected_across_files(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "b.st").write_text("PROGRAM B\nVAR x : INT; END_VAR\nx := nope_b;\nEND_PROGRAM\n")
    (tmp_path / "a.st").write_text("PROGRAM A\nVAR x : INT; END_VAR\nx := 'a';\nx := nope_a;\nEND_PROGRAM\n")
    rc, _, err = cli(["check", "b.st", "a.st"])
    heads = [l for l in err.splitlines() if ERROR_LINE.match(l)]
    assert rc == 1
    assert [h.split(": error:")[0] for h in heads] == ["a.st:3:6", "a.st:4:6", "b.st:3:6"]
    assert err.rstrip().endswith("3 error(s)")


def test_check_reads_every_file_before_resolving(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "main.st").write_text("PROGRAM Main\nVAR f : LaterFB; p : LaterType; END_VAR\nf();\nEND_PROGRAM\n")
    (tmp_path / "lib.st").write_text("FUNCTION_BLOCK LaterFB\nEND_FUNCTION_BLOCK\nTYPE LaterType : INT; END_TYPE\n")
    assert cli(["check", "main.st", "lib.st"])[0] == 0
    assert cli(["check", "lib.st", "main.st"])[0] == 0
    rc, _, err = cli(["check", "main.st"])
    assert rc == 1 and "LaterFB" in err and "LaterType" in err
