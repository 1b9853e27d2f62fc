"""`stvm lint` on object-oriented sources: METHOD / PROPERTY / EXTENDS / INTERFACE never crash the
linter, and an FB whose methods or base body assign its variables gets no "never assigned" /
"never read" findings from a body that alone does not show them."""

from __future__ import annotations

from pathlib import Path

import pytest

from lint_helpers import codes

ROOT = Path(__file__).resolve().parents[2]

OO = """
INTERFACE I_Dev
METHOD Start : BOOL
END_METHOD
END_INTERFACE

FUNCTION_BLOCK ABSTRACT FB_Base IMPLEMENTS I_Dev
VAR_OUTPUT calls : INT; END_VAR
VAR seen : INT; END_VAR
calls := calls + 1;
METHOD Start : BOOL
seen := seen + 1;
Start := seen > 1;
END_METHOD
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Dev EXTENDS FB_Base
VAR_OUTPUT ready : BOOL; END_VAR
VAR scratch : INT; END_VAR
scratch := 3;                 (* read by the method below *)
SUPER^();
METHOD Report : INT
Report := scratch;
ready := TRUE;                (* the output is assigned here, not in the body *)
END_METHOD
PROPERTY Count : INT
GET
Count := calls;
END_GET
END_PROPERTY
END_FUNCTION_BLOCK

PROGRAM Main
VAR d : FB_Dev; itf : I_Dev; ok : BOOL; n : INT; END_VAR
d();
itf := d;
ok := itf.Start();
n := d.Report() + d.Count;
END_PROGRAM
"""


def test_oo_source_lints_without_false_unassigned_or_unused():
    found = codes(OO)
    assert "SA102" not in found and "SA103" not in found


@pytest.mark.parametrize("folder", ["st_src/schneider/oo"])
def test_lint_runs_on_the_oo_demo(folder):
    from core_helpers import cli
    rc, out, err = cli(["lint", ROOT / folder])
    assert "Traceback" not in err and "internal error" not in err
    assert rc in (0, 1)


def _fb(middle: str) -> str:
    return f"""
FUNCTION_BLOCK F
VAR_OUTPUT q : INT; END_VAR
VAR d : INT; END_VAR
d := 0;
{middle}
IF d <> 0 THEN
    q := 1;
END_IF;
METHOD Reset
d := 5;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main VAR f : F; END_VAR
f();
END_PROGRAM
"""


def test_a_method_call_forgets_what_the_body_knew_about_the_instance():
    # Reset() sets d: the branch is live (without forgetting, SA402 would call it dead)
    assert "SA402" not in codes(_fb("Reset();"))
    assert "SA402" not in codes(_fb("THIS^.Reset();"))


def test_the_same_without_the_method_call_is_reported():
    assert "SA402" in codes(_fb(""))


def test_method_bodies_are_linted_like_functions():
    from lint_helpers import findings
    found = findings("""
FUNCTION_BLOCK F
VAR n : INT; END_VAR
METHOD Next : INT
VAR_INST kept : INT; END_VAR
VAR fresh : INT; END_VAR
kept := kept + 1;              (* VAR_INST lives in the instance: no finding *)
fresh := fresh + 1;            (* a method's VAR starts at 0 on every call: SA101 *)
IF kept > 3 THEN
    Next := fresh;             (* not assigned when kept <= 3: SA103 *)
END_IF;
END_METHOD
PROPERTY P : INT
GET
P := n;
END_GET
END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM Main VAR f : F; x : INT; END_VAR
x := f.Next() + f.P;
END_PROGRAM
""")
    got = sorted((f.code, f.span.line) for f in findings_of(found))
    assert ("SA101", 8) in got
    assert any(code == "SA103" for code, _ in got)
    assert not any(line in (7, 15) for _, line in got)


def findings_of(found):
    return [f for f in found if f.code in ("SA101", "SA102", "SA103")]


ITF_CALL = """
INTERFACE ICalc
METHOD Calc : INT
VAR_INPUT a : INT; END_VAR
END_METHOD
END_INTERFACE

FUNCTION_BLOCK Doubler IMPLEMENTS ICalc
METHOD Calc : INT
VAR_INPUT a : INT; END_VAR
Calc := a * 2;
END_METHOD
END_FUNCTION_BLOCK

FUNCTION_BLOCK User
VAR itf : ICalc; d : Doubler; END_VAR
itf := d;
itf.Calc(3);
END_FUNCTION_BLOCK

PROGRAM Main
VAR u : User; END_VAR
u();
END_PROGRAM
"""


def test_an_interface_variable_used_only_to_call_a_method_is_read():
    """`itf.M()` reads itf (issue 34 item 12: SA102 said "written but never read")."""
    assert "SA102" not in codes(ITF_CALL)
    unused = ITF_CALL.replace("itf.Calc(3);", "d.Calc(3);")
    assert "SA102" in codes(unused)   # written, and really never read now
