"""Checker rules of object orientation, one small source each: every error is
`FILE:LINE:COL: error: message` with an excerpt, never a traceback (the larger snapshots are
tests/semantics/diagnostics/oo_*.st)."""

from __future__ import annotations

import re

import pytest

from core_helpers import check_text, cli, write_st

HEAD = re.compile(r"^(?:.*/)?case\.st:(\d+):(\d+): error: (.+?)(?: \[E\d{3}\])?$", re.M)   # message, no code


def errors(source: str) -> list[tuple[int, str]]:
    rc, err = check_text(source)
    assert "Traceback" not in err and "internal error" not in err
    found = [(int(m[1]), m[3]) for m in HEAD.finditer(err)]
    assert rc == (1 if found else 0), err
    return found


def test_a_clean_oo_source_checks():
    assert errors("""
INTERFACE I
METHOD M : INT
VAR_INPUT a : INT; END_VAR
END_METHOD
END_INTERFACE
FUNCTION_BLOCK ABSTRACT B IMPLEMENTS I
METHOD ABSTRACT M : INT
VAR_INPUT a : INT; END_VAR
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK F EXTENDS B
METHOD M : INT
VAR_INPUT a : INT; END_VAR
M := a;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : F; i : I; x : INT; END_VAR
i := f;
x := i.M(1) + f.M(a := 2);
END_PROGRAM
""") == []


@pytest.mark.parametrize("source, line, message", [
    # a derived FB redeclares a variable of its base
    ("FUNCTION_BLOCK B\nVAR_INPUT k : INT; END_VAR\nEND_FUNCTION_BLOCK\n"
     "FUNCTION_BLOCK D EXTENDS B\nVAR k : INT; END_VAR\nEND_FUNCTION_BLOCK\n",
     5, "'k' is already declared in the base function block B"),
    # methods in a FUNCTION
    ("FUNCTION F : INT\nMETHOD M\nEND_METHOD\nF := 1;\nEND_FUNCTION\n",
     2, "a FUNCTION has no methods or properties"),
    # an interface method with statements
    ("INTERFACE I\nMETHOD M : INT\nM := 1;\nEND_METHOD\nEND_INTERFACE\n",
     3, "method 'M' of interface I cannot have statements"),
    # SUPER^() without a base, and SUPER^() inside an expression
    ("FUNCTION_BLOCK F\nSUPER^();\nEND_FUNCTION_BLOCK\n", 2, "SUPER: F does not EXTEND a function block"),
    # ABSTRACT on a PROGRAM
    ("PROGRAM ABSTRACT P\nEND_PROGRAM\n", 1, "ABSTRACT is only allowed on a FUNCTION_BLOCK"),
    # two methods of one name
    ("FUNCTION_BLOCK F\nMETHOD M\nEND_METHOD\nMETHOD M\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
     4, "duplicate method 'M' in F"),
    # a method named like a variable
    ("FUNCTION_BLOCK F\nVAR m : INT; END_VAR\nMETHOD M\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
     3, "'M' is both a variable and a method of F"),
    # IMPLEMENTS of something that is no interface
    ("FUNCTION_BLOCK B\nEND_FUNCTION_BLOCK\nFUNCTION_BLOCK F IMPLEMENTS B\nEND_FUNCTION_BLOCK\n",
     3, "'B' is not an interface"),
    # EXTENDS of an interface by an FB
    ("INTERFACE I\nEND_INTERFACE\nFUNCTION_BLOCK F EXTENDS I\nEND_FUNCTION_BLOCK\n",
     3, "'I' is not a function block; cannot extend"),
    # a property without SET written, without GET read
    ("FUNCTION_BLOCK F\nVAR v : INT; END_VAR\nPROPERTY P : INT\nGET\nP := v;\nEND_GET\nEND_PROPERTY\n"
     "END_FUNCTION_BLOCK\nPROGRAM Main\nVAR f : F; END_VAR\nf.P := 1;\nEND_PROGRAM\n",
     11, "property 'P' has no SET; it can only be read"),
    ("FUNCTION_BLOCK F\nVAR v : INT; END_VAR\nPROPERTY P : INT\nSET\nv := P;\nEND_SET\nEND_PROPERTY\n"
     "END_FUNCTION_BLOCK\nPROGRAM Main\nVAR f : F; x : INT; END_VAR\nx := f.P;\nEND_PROGRAM\n",
     11, "property 'P' has no GET; it can only be written"),
    # an instance of an unrelated FB for a base-typed in-out
    ("FUNCTION_BLOCK B\nEND_FUNCTION_BLOCK\nFUNCTION_BLOCK O\nEND_FUNCTION_BLOCK\n"
     "FUNCTION Use : INT\nVAR_IN_OUT b : B; END_VAR\nUse := 1;\nEND_FUNCTION\n"
     "PROGRAM Main\nVAR o : O; x : INT; END_VAR\nx := Use(o);\nEND_PROGRAM\n",
     11, "in-out 'b' of Use is B; got O"),
    # a method call where a method result is needed
    ("FUNCTION_BLOCK F\nMETHOD M\nEND_METHOD\nEND_FUNCTION_BLOCK\n"
     "PROGRAM Main\nVAR f : F; x : INT; END_VAR\nx := f.M();\nEND_PROGRAM\n",
     7, "this call has no result value"),
    # an interface assigned an interface it does not extend
    ("INTERFACE I1\nEND_INTERFACE\nINTERFACE I2\nEND_INTERFACE\n"
     "PROGRAM Main\nVAR a : I1; b : I2; END_VAR\na := b;\nEND_PROGRAM\n",
     7, "interface I2 does not extend I1"),
    # __QUERYINTERFACE needs an interface variable to fill
    ("INTERFACE I\nEND_INTERFACE\nPROGRAM Main\nVAR a : I; ok : BOOL; n : INT; END_VAR\n"
     "ok := __QUERYINTERFACE(a, n);\nEND_PROGRAM\n",
     5, "the second argument of __QUERYINTERFACE must be an interface variable"),
])
def test_oo_errors(source, line, message):
    found = errors(source)
    assert any(l == line and message in m for l, m in found), found


PROPERTY_FB = """
FUNCTION_BLOCK F
VAR v : INT; END_VAR
PROPERTY P : INT
GET P := v; END_GET
SET v := P; END_SET
END_PROPERTY
METHOD M
VAR_OUTPUT q : INT; END_VAR
q := 1;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION Inc : INT
VAR_IN_OUT x : INT; END_VAR
x := x + 1;
Inc := x;
END_FUNCTION
"""


@pytest.mark.parametrize("statement, message", [
    ("f.M(q => g.P);", "the output q needs a variable; property 'P'"),
    ("k := Inc(g.P);", "the in-out x needs a variable; property 'P'"),
    ("r := REF(g.P);", "REF() needs a variable; property 'P'"),
])
def test_a_property_is_no_variable_to_bind(statement, message):
    found = errors(PROPERTY_FB + f"PROGRAM Main VAR f : F; g : F; r : REF_TO INT; k : INT; END_VAR\n{statement}\nEND_PROGRAM\n")
    assert [m for _, m in found if message in m], found


def test_a_property_is_no_for_variable():
    found = errors(PROPERTY_FB + "FUNCTION_BLOCK H EXTENDS F\nFOR P := 1 TO 3 DO END_FOR;\nEND_FUNCTION_BLOCK\n")
    assert [m for _, m in found if m.startswith("FOR needs a variable; property 'P'")], found


def test_calling_a_method_of_an_abstract_base_through_super_is_an_error():
    found = errors("""
FUNCTION_BLOCK ABSTRACT B
METHOD ABSTRACT M : INT
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK F EXTENDS B
METHOD M : INT
M := SUPER^.M();
END_METHOD
END_FUNCTION_BLOCK
""")
    assert found == [(8, "SUPER^.M: the method is ABSTRACT in B")]


def test_assigning_into_a_struct_property_is_an_error():
    found = errors("""
TYPE Pt : STRUCT x : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK F
VAR v : Pt; END_VAR
PROPERTY S : Pt
GET S := v; END_GET
SET v := S; END_SET
END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM Main VAR f : F; k : INT; END_VAR
f.S.x := 5;
k := f.S.x;
END_PROGRAM
""")
    assert found == [(11, "cannot assign into property 'S': its GET returns a copy; assign the whole property")]


@pytest.mark.parametrize("source, line, message", [
    # VAR_STAT is the POU's own: not an input or output of an instance
    ("FUNCTION_BLOCK F\nVAR_STAT s : INT; END_VAR\nEND_FUNCTION_BLOCK\n"
     "PROGRAM Main\nVAR f : F; x : INT; END_VAR\nx := f.s;\nEND_PROGRAM\n", 6, "function block F has no member 's'"),
    # one name in VAR and VAR_STAT
    ("FUNCTION_BLOCK F\nVAR s : INT; END_VAR\nVAR_STAT s : INT; END_VAR\nEND_FUNCTION_BLOCK\n",
     3, "duplicate declaration of 's' in F"),
    # in a method: one name in VAR and VAR_STAT, and VAR_STAT in an interface's method
    ("FUNCTION_BLOCK F\nMETHOD M\nVAR s : INT; END_VAR\nVAR_STAT s : INT; END_VAR\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
     4, "duplicate declaration of 's' in M"),
    ("INTERFACE I\nMETHOD M\nVAR_STAT s : INT; END_VAR\nEND_METHOD\nEND_INTERFACE\n",
     3, "an interface method declares only inputs, outputs and in-outs, not VAR_STAT"),
    # a VAR_STAT CONSTANT stays a constant
    ("FUNCTION F : INT\nVAR_STAT CONSTANT k : INT := 3; END_VAR\nk := 4;\nF := k;\nEND_FUNCTION\n",
     3, "constant"),
])
def test_var_stat_errors(source, line, message):
    found = errors(source)
    assert any(l == line and message in m for l, m in found), found


def test_var_stat_in_functions_methods_and_fbs_checks():
    assert errors("FUNCTION F : INT\nVAR_STAT n : INT := 1; END_VAR\nn := n + 1;\nF := n;\nEND_FUNCTION\n"
                  "FUNCTION_BLOCK B\nVAR_STAT k : INT; END_VAR\nk := k + 1;\n"
                  "METHOD M : INT\nVAR_STAT c : INT; END_VAR\nc := c + k;\nM := c;\nEND_METHOD\n"
                  "END_FUNCTION_BLOCK\n") == []


FB_FOR_INIT = ("FUNCTION_BLOCK F\nVAR_INPUT x : INT; END_VAR\nVAR_IN_OUT io : INT; END_VAR\n"
               "VAR_TEMP tmp : INT; END_VAR\nVAR CONSTANT k : INT := 1; END_VAR\nEND_FUNCTION_BLOCK\n")


@pytest.mark.parametrize("decl, message", [
    ("a : F := (nope := 1);", "function block F has no variable 'nope' to initialise"),
    ("b : F := (io := 1);", "'io' of F is an in-out (a reference, bound at each call): an instance initialiser"),
    ("c : F := (tmp := 1);", "'tmp' of F is a VAR_TEMP (fresh at each call)"),
    ("d : F := (k := 2);", "'k' of F is a constant: an instance initialiser cannot set it"),
    ("e : F := (x := 70000);", "70000 is out of range for INT"),
    ("h : F := (x := 1, x := 2);", "'x' is initialised twice"),
    ("i : F := 3;", "initial value"),
])
def test_fb_instance_initialiser_errors(decl, message):
    found = errors(FB_FOR_INIT + f"PROGRAM Main\nVAR {decl} END_VAR\nEND_PROGRAM\n")
    assert any(l == 8 and message in m for l, m in found), found


@pytest.mark.parametrize("source, line, message", [
    ("FUNCTION_BLOCK F\nMETHOD FB_init : BOOL\nVAR_INPUT bInitRetains : BOOL; END_VAR\nEND_METHOD\n"
     "END_FUNCTION_BLOCK\n", 2, "FB_init needs the inputs bInitRetains and bInCopyCode of type BOOL"),
    ("FUNCTION_BLOCK F\nMETHOD FB_init : BOOL\nVAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR\n"
     "VAR_OUTPUT q : INT; END_VAR\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
     4, "FB_init takes inputs only (stvm calls it at instance creation), not VAR_OUTPUT 'q'"),
    ("FUNCTION_BLOCK F\nMETHOD FB_exit : BOOL\nVAR_INPUT bInCopyCode : INT; END_VAR\nEND_METHOD\n"
     "END_FUNCTION_BLOCK\n", 2, "FB_exit needs the input bInCopyCode of type BOOL"),
])
def test_fb_init_and_fb_exit_signatures(source, line, message):
    found = errors(source)
    assert any(l == line and message in m for l, m in found), found


FB_WITH_INIT = """FUNCTION_BLOCK F
VAR n : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; a : INT; nMax : INT := 100; END_VAR
n := a + nMax;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK H
END_FUNCTION_BLOCK
FUNCTION_BLOCK G EXTENDS F
END_FUNCTION_BLOCK
"""


def test_fb_init_arguments_in_declarations_check_clean():
    assert errors(FB_WITH_INIT + "VAR_GLOBAL gf : F(7, 8); END_VAR\nPROGRAM Main\nVAR f1 : F(1, 2); "
                  "f2 : F(nMax := 5) := (n := 1); f3 : F(); g : G(a := 1, nMax := -1); END_VAR\nEND_PROGRAM\n") == []


@pytest.mark.parametrize("decl, column, message", [
    ("e : F(1, 2, 3);", 13, "too many FB_init arguments: F's FB_init takes 2 besides bInitRetains and bInCopyCode"),
    ("e : F(b := 3);", 7, "F's FB_init has no input 'b'"),
    ("e : F(a := 1, a := 2);", 15, "FB_init input 'a' is given twice"),
    ("e : H(1);", 5, "function block H has no FB_init method to take arguments"),
    ("e : INT(1, 2);", 5, "arguments in parentheses after a type are FB_init arguments, but INT is not a function block"),
    ("e : F(v, 1);", 7, "an FB_init argument in a declaration must be a constant expression"),
    ("e : F(1);", 5, "1 FB_init argument for 2 inputs of F's FB_init: give all of them, or name them"),
    ("e : F(a := 1, 2);", 15, "a positional FB_init argument after a named one"),
    ("e : F(a := 100000);", 12, "100000 is out of range for INT (-32768..32767)"),
    ("e : F(bInitRetains := FALSE);", 7, "F's FB_init has no input 'bInitRetains' (stvm passes bInitRetains"),
    ("e : F(a => v);", 7, "FB_init takes inputs only: no '=>' in a declaration"),
])
def test_fb_init_argument_errors(decl, column, message):
    rc, err = check_text(FB_WITH_INIT + f"PROGRAM Main\nVAR\nv : INT;\n{decl}\nEND_VAR\nEND_PROGRAM\n")
    assert rc == 1 and "Traceback" not in err
    assert f"case.st:15:{column}: error: {message}" in err, err


@pytest.mark.parametrize("source, line, message", [
    ("FUNCTION_BLOCK F\n{attribute 'call_after_init'}\nMETHOD M\nVAR_INPUT a : INT; END_VAR\nEND_METHOD\n"
     "END_FUNCTION_BLOCK\n", 4, "a call_after_init method takes no parameters (stvm calls it at instance creation), "
     "not VAR_INPUT 'a'"),
    ("PROGRAM Main\n{attribute 'call_after_init'}\nMETHOD N\nEND_METHOD\nEND_PROGRAM\n", 3,
     "{attribute 'call_after_init'} is for a METHOD of a FUNCTION_BLOCK"),
])
def test_call_after_init_errors(source, line, message):
    found = errors(source)
    assert any(l == line and message in m for l, m in found), found


RECURSIVE_METHODS = """FUNCTION_BLOCK F
METHOD Down : INT
VAR_INPUT k : INT; END_VAR
IF k > 0 THEN Down := THIS^.Down(k - 1) + 1; END_IF
END_METHOD
METHOD A
B();
END_METHOD
METHOD B
THIS^.A();
END_METHOD
METHOD Ok
Down(1);
A();
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK G
VAR f : F; END_VAR
METHOD Outer
f.Ok();
END_METHOD
END_FUNCTION_BLOCK
"""


def test_a_recursive_method_is_an_error_under_iec_as_a_recursive_function_is():
    rc, _, err = cli(["check", write_st(RECURSIVE_METHODS), "--dialect", "iec"])
    found = [(int(m[1]), m[3]) for m in re.finditer(r":(\d+):(\d+): error: (.+) \[E\d{3}\]", err)]
    # the cycles are reported once each, at a method on them; callers of a cycle (Ok, G.Outer) are not
    assert rc == 1 and found == [
        (2, "recursive method call F.Down -> F.Down: IEC 61131-3 does not allow recursion"),
        (6, "recursive method call F.A -> F.B -> F.A: IEC 61131-3 does not allow recursion")], err


@pytest.mark.parametrize("dialect", ["codesys", "twincat"])
def test_a_recursive_method_is_a_warning_where_the_vendor_allows_it(dialect):
    rc, _, err = cli(["check", write_st(RECURSIVE_METHODS), "--dialect", dialect])
    assert rc == 0 and err.count(": warning: recursive method call") == 2, err
    assert f"F.Down -> F.Down: allowed in {dialect}, but a recursion too deep ends the run in a " \
           "stack-overflow fault" in err


def test_ref_to_an_interface_takes_only_references_to_that_interface():
    found = errors("INTERFACE I\nEND_INTERFACE\nFUNCTION_BLOCK F IMPLEMENTS I\nEND_FUNCTION_BLOCK\n"
                   "PROGRAM Main\nVAR f : F; r : REF_TO I; n : INT; END_VAR\nr := REF(f);\nr := REF(n);\n"
                   "r^ := n;\nEND_PROGRAM\n")
    # a REF_TO I holds the address of an interface variable, not of an instance (assign `r^ := f`)
    assert found == [(7, "type mismatch: cannot assign REF_TO F to REF_TO I"),
                     (8, "type mismatch: cannot assign REF_TO INT to REF_TO I"),
                     (9, "type mismatch: cannot assign INT to interface I")]
