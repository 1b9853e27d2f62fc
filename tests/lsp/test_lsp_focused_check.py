"""The focused check of the language server's driver (stvm/lsp/driver.py): after an edit, only
the edited file's bodies (and its dependents' when its declarations changed) are checked, and
the diagnostics are those of a full check of the same texts."""

from __future__ import annotations

from pathlib import Path

from lsp_helpers import FIXTURES, ROOT
from stvm.lsp.driver import Driver

OO = FIXTURES / "oo"
MAIN, AXIS = (OO / "main.st").resolve(), (OO / "axis.st").resolve()
THESIS = (ROOT / "st_src" / "PnP_Example.st").resolve()


def verdict(result) -> list[tuple]:
    return [(d.span.file, d.span.line, d.span.column, d.code, d.message) for d in result.diagnostics]


def edit(path: Path, old: str, new: str) -> dict[str, str]:
    text = path.read_text(encoding="utf-8")
    assert old in text
    return {str(path): text.replace(old, new, 1)}


def focused_and_full(path: Path, buffers: dict[str, str]):
    driver = Driver()
    previous = driver.check(path, {})
    assert not previous.focused
    focused = driver.check(path, buffers, focus=True, previous=previous)
    full = driver.check(path, buffers)      # the same driver: each text is parsed once
    assert not full.focused
    return focused, full


def test_an_edit_inside_a_body_checks_that_file_only_and_agrees_with_the_full_check():
    focused, full = focused_and_full(MAIN, edit(MAIN, "reading := drive.Position", "reading := drive.Positio"))
    assert focused.focused == {str(MAIN)}
    assert verdict(focused) == verdict(full) and any(d.code == "E034" for d in full.diagnostics)


def test_an_edit_of_a_declaration_rechecks_the_files_that_use_it():
    # FB_Axis's method renamed in axis.st: main.st, which calls it, is re-checked and gets the error
    focused, full = focused_and_full(AXIS, edit(AXIS, "METHOD MoveTo : BOOL\nVAR_INPUT\n    target : REAL;\nEND_VAR\n"
                                                      "posNow", "METHOD MoveTo2 : BOOL\nVAR_INPUT\n    target : REAL;\n"
                                                      "END_VAR\nposNow"))
    assert str(MAIN) in focused.focused and str(AXIS) in focused.focused
    assert verdict(focused) == verdict(full) and full.diagnostics


def test_a_fixed_error_is_cleared_by_the_focused_check():
    driver = Driver()
    broken = edit(MAIN, "reading := drive.Position", "reading := drive.Positio")
    previous = driver.check(MAIN, broken)
    assert previous.diagnostics
    fixed = driver.check(MAIN, {}, focus=True, previous=previous)
    assert fixed.focused and fixed.diagnostics == []


def test_a_full_check_when_a_focused_one_cannot_be_made():
    driver = Driver()
    previous = driver.check(MAIN, {})
    two = {**edit(MAIN, "reading := drive.Position", "reading := drive.Positio"),
           **edit(AXIS, "posNow := target;", "posNow := target + 1.0;")}
    assert not driver.check(MAIN, two, focus=True, previous=previous).focused          # two files changed
    assert not driver.check(MAIN, {}, focus=True, previous=None).focused              # nothing to start from
    types = (OO / "types.st").resolve()
    text = types.read_text(encoding="utf-8")
    assert not driver.check(types, {str(types): text + "\nTYPE E_More : (A, B); END_TYPE\n"}, focus=True,
                            previous=previous).focused                                 # a TYPE changed


def test_the_thesis_project_focused_agrees_with_full():
    focused, full = focused_and_full(THESIS, edit(THESIS, "Prg_Step:=1;", "Prg_Step:=UndeclaredName; Prg_Step:=TRUE;"))
    assert focused.focused == {str(THESIS)}
    assert verdict(focused) == verdict(full) and full.diagnostics


def test_a_stdlib_function_named_first_by_the_edit_is_checked_as_in_the_full_check():
    # the focused check declares only the stdlib POUs the project names: a call of one that no
    # file named before (wrong argument types, then a right call) gets the full check's verdict
    for call in ("reading := CONCAT(1, 2);", "reading := LREAL_TO_REAL(SQRT(2.0));", "reading := NoSuchPou(1);"):
        focused, full = focused_and_full(MAIN, edit(MAIN, "reading := drive.Position", call + "\nreading := drive.Position"))
        assert focused.focused == {str(MAIN)}
        assert verdict(focused) == verdict(full)
    assert any(d.code for d in full.diagnostics)


def test_the_full_check_gives_the_verdict_of_stvm_check(tmp_path):
    # the driver's full check reads only the stdlib's declarations (its bodies give nothing the
    # editor shows): the diagnostics are still those of `stvm check` (a copy of the oo fixture
    # with errors in two files; the thesis project, clean)
    import shutil
    from stvm.project import check
    shutil.copytree(OO, tmp_path / "oo")
    main, axis = tmp_path / "oo" / "main.st", tmp_path / "oo" / "axis.st"
    main.write_text(main.read_text(encoding="utf-8").replace("drive.Position", "drive.Positio"), encoding="utf-8")
    axis.write_text(axis.read_text(encoding="utf-8").replace("posNow := target;", "posNow := 'text';"), encoding="utf-8")
    for path in (main.resolve(), THESIS):
        result = Driver().check(path, {})
        _, diags, _ = check([path.parent], use_cache=False)
        assert verdict(result) == [(d.span.file, d.span.line, d.span.column, d.code, d.message) for d in diags]
        assert (path == THESIS) == (diags == [])


def test_an_unopened_file_changed_on_disk_and_a_new_file_are_seen(tmp_path):
    (tmp_path / "a.st").write_text("PROGRAM A\nVAR x : INT; END_VAR\nx := Helper(1);\nEND_PROGRAM\n", encoding="utf-8")
    helper = tmp_path / "b.st"
    helper.write_text("FUNCTION Helper : INT\nVAR_INPUT v : INT; END_VAR\nHelper := v;\nEND_FUNCTION\n", encoding="utf-8")
    a = (tmp_path / "a.st").resolve()
    driver = Driver()
    assert driver.check(a, {}).diagnostics == []
    # another program renames the function: the stat of b.st changed, so it is read again
    helper.write_text("FUNCTION Helper2 : INT\nVAR_INPUT v : INT; END_VAR\nHelper2 := v;\nEND_FUNCTION\n"
                      "\n(* longer *)\n", encoding="utf-8")
    assert any("Helper" in d.message for d in driver.check(a, {}).diagnostics)
    # a new file of the folder declares it again: the folder's stat changed, the project is re-read
    (tmp_path / "c.st").write_text("FUNCTION Helper : INT\nVAR_INPUT v : INT; END_VAR\nHelper := v + 1;\nEND_FUNCTION\n",
                                   encoding="utf-8")
    result = driver.check(a, {})
    assert str((tmp_path / "c.st").resolve()) in result.files and result.diagnostics == []
