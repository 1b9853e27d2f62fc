"""Pragmas and attributes anywhere CODESYS/TwinCAT write them, `qualified_only` honoured, the
rest ignored; qualified names `GVL.x` and `Enum.member` (stvm/syntax/pragmas.py,
stvm/semantics/qualified.py)."""

from __future__ import annotations

import shutil
from pathlib import Path

from stvm.syntax.parser import parse_text
from stvm.syntax.pragmas import attribute, has_attribute
from tests.core_helpers import assert_no_traceback, check_text, cli, run_st

TWINCAT = Path(__file__).parent / "data" / "twincat"

EVERYWHERE = """
{attribute 'qualified_only'}
{attribute 'strict'}
TYPE
  {attribute 'hide'}
  E_Light : (Off, Amber, Green) := Off;
  ST_Pair :
  STRUCT
    {attribute 'hide'}
    a : INT;
    b : INT; {attribute 'pack_mode' := '1'}
  END_STRUCT
END_TYPE

{attribute 'qualified_only'}
VAR_GLOBAL
  {attribute 'hide'}
  gCount : INT;
END_VAR

{warning 'this program is a test'}
{attribute 'call_after_init'}
PROGRAM Main
{attribute 'no_check'}
VAR
  {attribute 'hide'}
  x : INT; {attribute 'instance-path'}
  {IF NOT defined (NO_Y)}
  y : INT := 5;
  {END_IF}
  light : E_Light;
  pair : ST_Pair;
END_VAR
{region 'counting'}
x := x + {info 'one'} 1;
{IF defined(SIMULATION)}
y := y + 1;
{ELSE}
y := y + 2;
{END_IF}
{endregion}
IF x > 1 THEN light := E_Light.Green; ELSE light := E_Light#Amber; END_IF
CASE light OF
  E_Light.Amber: pair.a := 1;
  E_Light.Green: pair.b := 2;
END_CASE
gCount := gCount + 1;
END_PROGRAM
"""


def test_pragmas_anywhere_are_ignored_and_the_program_runs():
    values = run_st(EVERYWHERE, cycles=2, prints=["Main.x", "Main.y", "Main.light", "Main.pair.a", "Main.pair.b",
                                                  "gCount"], fmt=True)
    # conditional compilation is evaluated (tests/syntax/test_conditional.py): SIMULATION is not
    # defined, so the {ELSE} branch runs
    assert values == {"Main.x": "2", "Main.y": "9", "Main.light": "E_Light#Green", "Main.pair.a": "1",
                      "Main.pair.b": "2", "gCount": "2"}


def test_leading_pragmas_are_attached_to_their_element():
    unit, diags = parse_text(EVERYWHERE, "p.st")
    assert not diags
    light, pair = unit.types
    assert light.pragmas == ("attribute 'qualified_only'", "attribute 'strict'", "attribute 'hide'")
    assert pair.pragmas == ()            # the struct's pragmas are inside it, on its fields
    (gvl,) = unit.globals
    assert gvl.pragmas == ("attribute 'qualified_only'",) and gvl.gvl == ""
    (main,) = unit.pous
    assert main.pragmas == ("warning 'this program is a test'", "attribute 'call_after_init'")


def test_attribute_syntax():
    assert attribute("attribute 'qualified_only'") == ("qualified_only", "")
    assert attribute(" attribute 'pack_mode' := '1' ") == ("pack_mode", "1")
    assert attribute("warning 'x'") is None
    assert has_attribute(("attribute 'Qualified_Only'",), "qualified_only")


def test_qualified_only_enum_needs_its_type():
    src = """
{attribute 'qualified_only'}
TYPE E_Mode : (Manual, Auto); END_TYPE
PROGRAM Main
VAR m : E_Mode; n : E_Mode := Auto; END_VAR
m := Manual;
m := E_Mode.Auto;
m := E_Mode#Manual;
END_PROGRAM
"""
    rc, err = check_text(src, "qo_enum.st")
    assert rc == 1
    assert_no_traceback(err)
    assert "qo_enum.st:5:31: error: 'Auto' is an enumerator of E_Mode, which is {attribute 'qualified_only'}: " \
           "write E_Mode.Auto" in err
    assert "qo_enum.st:6:6: error: 'Manual' is an enumerator of E_Mode" in err
    assert err.count(": error:") == 2


def test_enumerator_with_its_type_and_a_dot_in_plain_st():
    src = """
TYPE Color : (Red, Green, Blue); END_TYPE
PROGRAM Main
VAR c : Color := Color.Green; k : INT; END_VAR
CASE c OF
  Color.Red: k := 1;
  Color.Green, Color.Blue: k := 2;
END_CASE
IF c = Color.Green THEN c := Color.Blue; END_IF
END_PROGRAM
"""
    assert run_st(src, prints=["Main.c", "Main.k"], fmt=True) == {"Main.c": "Color#Blue", "Main.k": "2"}


def test_a_local_shadows_a_type_name_for_dotted_access():
    src = """
TYPE Pt : STRUCT Red : INT; END_STRUCT; END_TYPE
TYPE Color : (Red, Green); END_TYPE
PROGRAM Main
VAR Color : Pt; k : INT; END_VAR
Color.Red := 4;
k := Color.Red;
END_PROGRAM
"""
    assert run_st(src, prints=["Main.k"]) == {"Main.k": 4}


def _copy(tmp_path: Path) -> Path:
    target = tmp_path / "plc"
    shutil.copytree(TWINCAT, target)
    return target


def test_qualified_only_gvl_rejects_unqualified_use(tmp_path):
    folder = _copy(tmp_path)
    main = folder / "POUs" / "MAIN.TcPOU"
    xml = main.read_text(encoding="utf-8").replace("nStep := GVL_Main.nStep", "nStep := nStep")
    main.write_text(xml, encoding="utf-8")
    rc, _, err = cli(["check", folder])
    assert rc == 1
    assert_no_traceback(err)
    offset = xml.index("nStep := nStep") + len("nStep := ")
    line = xml.count("\n", 0, offset) + 1
    col = offset - xml.rfind("\n", 0, offset)
    assert f"{main}:{line}:{col}: error: 'nStep' is in the global variable list GVL_Main, which is " \
           f"{{attribute 'qualified_only'}}: write GVL_Main.nStep" in err


def test_gvl_without_qualified_only_takes_both_forms(tmp_path):
    folder = _copy(tmp_path)
    gvl = folder / "GVLs" / "GVL_Main.TcGVL"
    gvl.write_text(gvl.read_text(encoding="utf-8").replace("{attribute 'qualified_only'}\n", ""), encoding="utf-8")
    main = folder / "POUs" / "MAIN.TcPOU"
    main.write_text(main.read_text(encoding="utf-8").replace("stData.nValue := fbCounter.nCount;",
                                                             "stData.nValue := fbCounter.nCount + nStep - GVL_Main.nStep;"),
                    encoding="utf-8")
    rc, out, err = cli(["run", folder, "--cycles", "3", "--print", "MAIN.stData.nValue", "--no-cache"])
    assert (rc, out) == (0, "MAIN.stData.nValue = 6\n"), err


def test_pragmas_cannot_hide_code_or_break_strings():
    src = """PROGRAM Main
VAR s : STRING[20] := '{not a pragma}'; n : INT; END_VAR
(* {attribute 'in a comment'} *)
n := LEN(s);
END_PROGRAM
"""
    assert run_st(src, prints=["Main.s", "Main.n"], fmt=True) == {"Main.s": "'{not a pragma}'", "Main.n": "14"}
