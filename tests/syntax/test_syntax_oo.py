"""Object-oriented declarations in the syntax tree: METHOD (before or after an FB's statements,
with modifiers and a result type), FUNCTION_BLOCK EXTENDS / IMPLEMENTS / ABSTRACT / FINAL,
INTERFACE (EXTENDS, methods, properties), PROPERTY with GET / SET, THIS^ / SUPER^."""

from __future__ import annotations

import pytest

from stvm.syntax import nodes as n
from stvm.syntax.parser import parse_text


def _unit(text: str) -> n.CompilationUnit:
    unit, diags = parse_text(text, "t.st")
    assert not [d for d in diags if d.severity.name == "ERROR"], diags
    return unit


def test_methods_before_and_after_the_body():
    fb = _unit("""
FUNCTION_BLOCK F
VAR x : INT; END_VAR
METHOD First : INT
VAR_INPUT a : INT; END_VAR
First := a;
END_METHOD
x := 1;
x := 2;
METHOD PRIVATE Second
END_METHOD;
END_FUNCTION_BLOCK""").pous[0]
    assert [type(s) for s in fb.body] == [n.Assign, n.Assign]
    first, second = fb.methods
    assert (first.name, first.modifiers, first.return_type.parts) == ("First", (), ("INT",))
    assert first.var_blocks[0].kind == "VAR_INPUT" and len(first.body) == 1
    assert (second.name, second.modifiers, second.return_type, second.body) == ("Second", ("PRIVATE",), None, ())


def test_fb_header_extends_implements_and_modifiers():
    fb = _unit("FUNCTION_BLOCK ABSTRACT Derived EXTENDS Base IMPLEMENTS I1, Lib\\I2 END_FUNCTION_BLOCK").pous[0]
    assert fb.modifiers == ("ABSTRACT",)
    assert fb.extends == (n.Name(("Base",)),)
    assert fb.implements == (n.Name(("I1",)), n.Name(("Lib", "I2")))


def test_interface_with_methods_properties_and_extends():
    itf = _unit("""
INTERFACE I_Motion EXTENDS I_Base, I_Other
METHOD MoveTo : BOOL
VAR_INPUT x : LREAL; END_VAR
END_METHOD
PROPERTY Speed : LREAL
GET
END_GET
SET
END_SET
END_PROPERTY
END_INTERFACE""").pous[0]
    assert itf.kind == "INTERFACE" and itf.name == "I_Motion"
    assert [e.parts for e in itf.extends] == [("I_Base",), ("I_Other",)]
    assert [m.name for m in itf.methods] == ["MoveTo"]
    (prop,) = itf.properties
    assert prop.name == "Speed" and prop.getter is not None and prop.setter is not None


def test_property_with_get_and_set_bodies():
    fb = _unit("""
FUNCTION_BLOCK F
VAR v : INT; END_VAR
PROPERTY PUBLIC Value : INT
GET
VAR tmp : INT; END_VAR
tmp := v;
Value := tmp;
END_GET
SET
v := Value;
END_SET
END_PROPERTY
END_FUNCTION_BLOCK""").pous[0]
    (prop,) = fb.properties
    assert prop.modifiers == ("PUBLIC",) and prop.type_spec.parts == ("INT",)
    assert prop.getter.kind == "GET" and prop.getter.var_blocks[0].decls[0].names[0][0] == "tmp"
    assert len(prop.getter.body) == 2 and len(prop.setter.body) == 1


def test_this_and_super_are_dereferenced_names():
    fb = _unit("FUNCTION_BLOCK F EXTENDS B THIS^.x := SUPER^.Get(); SUPER^(); END_FUNCTION_BLOCK").pous[0]
    assign, call = fb.body
    assert assign.target == n.Member(n.Deref(n.Name(("THIS",))), "x")
    assert assign.value == n.Call(n.Member(n.Deref(n.Name(("SUPER",))), "Get"), ())
    assert call.call == n.Call(n.Deref(n.Name(("SUPER",))), ())


@pytest.mark.parametrize("word", ["final", "internal", "public", "get", "set"])
def test_modifier_words_stay_usable_as_variable_names(word):
    pou = _unit(f"PROGRAM P VAR {word} : INT; END_VAR {word} := {word} + 1; END_PROGRAM").pous[0]
    assert pou.body[0].target == n.Name((word,))


def test_method_outside_a_pou_is_a_syntax_error():
    _, diags = parse_text("METHOD M END_METHOD", "t.st")
    assert diags and diags[0].severity.name == "ERROR" and diags[0].span.line == 1


def test_oo_words_still_name_variables_at_the_start_of_a_statement():
    # ed. 2 code may call a variable `method`: METHOD/PROPERTY/EXTENDS/IMPLEMENTS are keywords only
    # where a name follows them
    fb = _unit("""
FUNCTION_BLOCK F
VAR method, property, extends, implements : INT; END_VAR
extends := 1;
method := method + 1;
property := method;
implements := property;
END_FUNCTION_BLOCK""").pous[0]
    assert [s.target.parts[0] for s in fb.body] == ["extends", "method", "property", "implements"]
    assert fb.methods == () and fb.extends == ()


def test_modifier_words_name_pous_and_methods():
    unit = _unit("""
FUNCTION_BLOCK Final
VAR_INPUT x : INT; END_VAR
END_FUNCTION_BLOCK
FUNCTION_BLOCK Internal EXTENDS Final
METHOD Public : INT
Public := x;
END_METHOD
METHOD PRIVATE FINAL Abstract
VAR_INPUT a : INT; END_VAR
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK ABSTRACT PUBLIC Shape
END_FUNCTION_BLOCK""")
    final, internal, shape = unit.pous
    assert (final.name, final.modifiers) == ("Final", ())
    assert (internal.name, internal.modifiers) == ("Internal", ())
    assert [(m.name, m.modifiers) for m in internal.methods] == [("Public", ()), ("Abstract", ("PRIVATE", "FINAL"))]
    assert (shape.name, shape.modifiers) == ("Shape", ("ABSTRACT", "PUBLIC"))


def test_fb_init_arguments_in_a_declaration_next_to_subranges_and_enums():
    """`fb : F(1, nMax := 5)` (CODESYS/TwinCAT) shares `Name (` with a subrange `INT(0..100)` and
    an enumeration with a base type `INT (a := 1)`: the grammar tells them apart after `(`."""
    unit = _unit("""
TYPE E : INT (a := 1, b := 2); END_TYPE
TYPE R : INT(0..100); END_TYPE
PROGRAM Main
VAR
  f1 : F(1, 2);
  f2 : Lib\\F(a := 3, nMax := 5) := (x := 4);
  f3 : F();
  f4 : F;
  r : INT(-5..5);
END_VAR
END_PROGRAM
""")
    enum, subrange = (d.body for d in unit.types)
    assert isinstance(enum, n.EnumDecl) and enum.base == "INT" and [m[0] for m in enum.members] == ["a", "b"]
    assert isinstance(subrange.type_spec, n.SubrangeTypeSpec) and subrange.type_spec.base == "INT"
    f1, f2, f3, f4, r = unit.pous[0].var_blocks[0].decls
    assert [(a.kind, a.value.value) for a in f1.fb_args] == [("positional", 1), ("positional", 2)]
    assert f2.type_spec.parts == ("Lib", "F") and [a.name for a in f2.fb_args] == ["a", "nMax"]
    assert isinstance(f2.init, n.StructInit)
    assert f3.fb_args == () and f4.fb_args is None and r.fb_args is None
    assert (r.type_spec.low, r.type_spec.high) == (-5, 5)


def test_fb_init_arguments_parse_the_same_with_lark_and_the_fast_driver():
    from stvm.syntax.parser import parse_text_lark
    text = "PROGRAM Main\nVAR f1 : F(1, -2); f2 : F(a := 3) := (x := 4); f3 : F(); r : INT(-5..5); END_VAR\nEND_PROGRAM\n"
    assert parse_text(text, "t.st")[0] == parse_text_lark(text, "t.st")[0]


def test_a_pragma_right_before_a_method_is_the_methods():
    fb = _unit("""
{attribute 'call_after_init'}
FUNCTION_BLOCK F
VAR x : INT; END_VAR
x := 1; {warning 'in the body'}
x := 2;
{attribute 'call_after_init'}
METHOD Ready
{attribute 'inside'}
x := 3;
END_METHOD
METHOD Other
END_METHOD
END_FUNCTION_BLOCK
""").pous[0]
    assert fb.pragmas == ("attribute 'call_after_init'",)
    assert [(m.name, m.pragmas) for m in fb.methods] == [("Ready", ("attribute 'call_after_init'",)), ("Other", ())]
