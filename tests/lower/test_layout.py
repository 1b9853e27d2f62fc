"""The layout of generated names (issue 18, item 3): `stvm/lower/layout.py`, the path accessor
built on it (`stvm/runtime/access.py`), the native FBs' ST names (`stvm/lower/bind.py`), and the
contract that nothing outside `stvm/lower` builds a storage name."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from core_helpers import start_st
from stvm.lower.bind import st_names
from stvm.lower.layout import FIELD, ProjectLayout, build_layout, is_storage_name, struct_layout
from stvm.lower.names import var_attr
from stvm.runtime.access import PathError, UnboundInOut, parse_path
from stvm.semantics import types as t

ROOT = Path(__file__).resolve().parents[2]

SOURCE = """
TYPE
    Point : STRUCT X : INT; Y : REAL; END_STRUCT;
    Holder : STRUCT P : Point; Tag : STRING[8]; END_STRUCT;
END_TYPE
VAR_GLOBAL
    G_Count : DINT := 5;
    G_Grid : ARRAY[1..2, 0..1] OF INT;
END_VAR
FUNCTION_BLOCK Inner
VAR_INPUT In1 : INT; END_VAR
VAR_OUTPUT Out1 : INT; END_VAR
VAR_IN_OUT Ref1 : INT; END_VAR
VAR Data : ARRAY[1..4] OF INT; END_VAR
VAR_TEMP Scratch : INT; END_VAR
VAR_EXTERNAL G_Count : DINT; END_VAR
Out1 := In1 + Ref1;
Data[3] := Out1;
METHOD Twice : INT
VAR_INPUT K : INT; END_VAR
Twice := 2 * K;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR
    Fb : Inner;
    Spare : Inner;
    Shared : INT := 4;
    H : Holder;
    Flag : BOOL;
    Name : STRING[4];
END_VAR
VAR_EXTERNAL G_Count : DINT; END_VAR
Fb(In1 := 1, Ref1 := Shared);
H.P.X := H.P.X + 1;
END_PROGRAM
"""


@pytest.fixture(scope="module")
def vm():
    machine = start_st(SOURCE)
    machine.run(cycles=1)
    return machine


# ---------------------------------------------------------------- the layout

def test_layout_is_published_on_the_lowered_project(vm):
    layouts = vm.project.lowered.layouts
    assert isinstance(layouts, ProjectLayout)
    assert vm.layouts is layouts


def test_pou_layout_has_every_variable_with_storage_type_and_section(vm):
    inner = vm.layouts.pous["inner"]
    assert inner.pou == "Inner" and inner.kind == "FUNCTION_BLOCK"
    sections = {slot.name: slot.section for slot in inner}
    assert sections == {"In1": "VAR_INPUT", "Out1": "VAR_OUTPUT", "Ref1": "VAR_IN_OUT", "Data": "VAR",
                        "Scratch": "VAR_TEMP", "G_Count": "VAR_EXTERNAL"}
    slot = inner.slot("out1")
    assert slot.storage == var_attr("Out1") and slot.type == t.INT
    assert isinstance(inner.slot("DATA").type, t.ArrayType)
    # what lives on the instance itself: not the in-out's reference, not the global
    assert [s.name for s in inner.owned()] == ["In1", "Out1", "Data", "Scratch"]
    assert inner.slot("nope") is None


def test_storage_names_are_the_ones_the_generated_class_has(vm):
    _, inst, _ = vm.instances["main"]
    main = vm.layouts.pous["main"]
    for slot in main.owned():
        assert hasattr(inst, slot.storage), slot
    assert not hasattr(inst, main.slot("G_Count").storage)   # an external lives on the globals
    for slot in vm.layouts.globals:
        assert hasattr(vm.globals, slot.storage) and slot.section == "VAR_GLOBAL"


def test_struct_layout_and_lookup_by_type(vm):
    holder_type = vm.layouts.pous["main"].slot("H").type
    layout = vm.layouts.of(holder_type)
    assert layout is vm.layouts.structs["holder"]
    assert [(s.name, s.section) for s in layout] == [("P", FIELD), ("Tag", FIELD)]
    assert layout.type is not None and layout.type.qualname.lower() == "holder"
    point = vm.layouts.of(layout.slot("p").type)
    assert [s.storage for s in point] == [var_attr("X"), var_attr("Y")]
    # a struct type on its own (no project at hand) gives the same storage names
    assert [s.storage for s in struct_layout(layout.slot("p").type)] == [s.storage for s in point]
    fb_type = vm.layouts.pous["main"].slot("Fb").type
    assert vm.layouts.of(fb_type) is vm.layouts.pous["inner"]
    assert vm.layouts.of(t.INT) is None and vm.layouts.of(None) is None


def test_methods_have_their_own_layout(vm):
    method = vm.layouts.pous["inner.twice"]
    assert method.kind == "METHOD" and method.slot("k").section == "VAR_INPUT"


def test_pin_aliases_reach_their_slot():
    # Omron spells TON's IN as `In` (iec_pin_aliases): the alias finds the same slot
    machine = start_st("PROGRAM Main VAR T : TON; END_VAR T(IN := TRUE, PT := T#1s); END_PROGRAM")
    ton = machine.layouts.pous["ton"]
    assert ton.slot("IN") is not None
    for alias, key in ton.aliases.items():
        assert ton.slot(alias) is ton.slots[key]


def test_build_layout_from_a_model_is_deterministic(vm):
    again = build_layout(vm.model)
    assert again.pous.keys() == vm.layouts.pous.keys()
    assert again.pous["main"] == vm.layouts.pous["main"]
    assert again.globals == vm.layouts.globals


def test_is_storage_name():
    assert is_storage_name(var_attr("Prg_Step"))
    for bad in ("Prg_Step", "v_", "v_x.y", "v_x; import os", "_impl", ""):
        assert not is_storage_name(bad), bad


# ---------------------------------------------------------------- the accessor

def test_paths_read_and_write_through_the_layout(vm):
    assert vm.get("Main.Fb.Data[3]") == 5          # Out1 = In1 + Ref1 = 1 + 4
    vm.set("Main.Fb.Data[3]", 11)
    assert vm["Main.fb.data[3]"] == 11
    assert vm.get("Main.H.P.X") == 1
    vm.set("Main.H.P.Y", 2.5)
    assert vm.format("Main.H.P") == "(X := 1, Y := 2.5)"
    assert vm.get("G_Count") == 5 and vm.get("Main.G_Count") == 5 and vm.get("Main.Fb.G_Count") == 5
    vm.set("G_Grid[2, 1]", 7)
    assert vm.get("G_Grid[2][1]") == 7 and vm.get("G_Grid")[1][1] == 7
    # an in-out reads and writes the variable the FB was called with
    vm.set("Main.Fb.Ref1", 9)
    assert vm.get("Main.Shared") == 9
    assert vm.type_of("Main.Fb.Ref1") == t.INT


def test_accessor_handle(vm):
    acc = vm.accessor("Main.Flag")
    assert acc.type == t.BOOL
    acc.set(True)
    assert acc.get() is True
    store = vm.accessor("Main.Shared").bind()
    store(3)
    assert vm.get("Main.Shared") == 3


@pytest.mark.parametrize("path, message", [
    ("Nope", "unknown variable 'Nope'"),
    ("Main", "names a program instance"),
    ("Main.Nope", "Main has no variable 'Nope'"),
    ("Main.Fb.Nope", "Inner has no member 'Nope'"),
    ("Main.H.Q", "Holder has no member 'Q'"),
    ("Main.Flag.X", "BOOL has no members"),
    ("Main.Fb.Data[5]", "index 5 outside 1..4"),
    ("Main.Fb.Data[0]", "index 0 outside 1..4"),
    ("Main.Fb.Data[x]", "an array index must be an integer"),
    ("Main.Fb.Data[1, 2]", "too many indices"),
    ("Main.Flag[1]", "not an array"),
    ("Main.Flag^", "needs a reference"),
    ("[1]", "a path starts with a name"),
    ("Main.Flag!", "unexpected '!'"),
])
def test_path_errors(vm, path, message):
    with pytest.raises(PathError, match=message.replace("[", r"\[").replace("]", r"\]").replace(".", r"\.")):
        vm.get(path)


def test_unbound_in_out_is_its_own_error(vm):
    with pytest.raises(UnboundInOut, match="not bound yet"):
        vm.get("Main.Spare.Ref1")


@pytest.mark.parametrize("path, value, message", [
    ("Main.Shared", "text", "INT"),
    ("Main.Shared", 40000, "out of range for INT"),
    ("Main.Flag", 2, "BOOL"),
    ("Main.H.P.X", 1.5, "INT"),
])
def test_write_of_the_wrong_type_is_refused(vm, path, value, message):
    before = vm.get(path)
    with pytest.raises((ValueError, TypeError), match=message):
        vm.set(path, value)
    assert vm.get(path) == before


def test_parse_path_tokens():
    assert parse_path("Main.fb.x[3]") == (("name", "Main"), ("name", "fb"), ("name", "x"), ("index", "3"))
    assert parse_path("r^") == (("name", "r"), ("deref", "^"))
    with pytest.raises(PathError):
        parse_path("")


# ---------------------------------------------------------------- native FBs: ST names

def test_st_names_binds_attributes_to_storage_names():
    @st_names("Execute", "Done")
    class Base:
        def call(self, inst):
            inst.Done = bool(inst.Execute)

    @st_names("ErrorID")
    class Derived(Base):
        def fail(self, inst):
            set_id = lambda: setattr(inst, "unused", 0) or inst.ErrorID   # nested code renamed too
            inst.ErrorID = 7
            return set_id()

    class Instance:
        __slots__ = (var_attr("Execute"), var_attr("Done"), var_attr("ErrorID"), "unused")

    inst = Instance()
    setattr(inst, var_attr("Execute"), True)
    Derived().call(inst)
    assert getattr(inst, var_attr("Done")) is True
    assert Derived().fail(inst) == 7 and getattr(inst, var_attr("ErrorID")) == 7
    assert Derived.__st_names__ == {"Execute": var_attr("Execute"), "Done": var_attr("Done"),
                                    "ErrorID": var_attr("ErrorID")}


def test_st_names_on_a_function():
    @st_names("Handle")
    def handle_of(socket):
        return socket.Handle

    class Socket:
        __slots__ = (var_attr("Handle"),)

    value = Socket()
    setattr(value, var_attr("Handle"), 3)
    assert handle_of(value) == 3


def test_st_names_refuses_a_name_used_as_a_global():
    with pytest.raises(TypeError, match="'Done' is used as a LOAD_GLOBAL"):
        @st_names("Done")
        def uses_global(inst):
            return Done   # noqa: F821

    with pytest.raises(TypeError, match="a class or a function"):
        st_names("Q")(42)


def test_every_native_fb_declares_ST_names_of_its_own_declaration():
    """The names a native FB binds are pins of its ST declaration or fields of the structs those
    pins hold, spelled as declared, so a misspelt or stale name fails here, not at a scan."""
    from stvm.settings import DEFAULT_SETTINGS, Dialect
    # a vendor's platform FBs (TwinCAT's GETCPUCOUNTER, ...) are in the stdlib of its dialect only
    machines = [start_st("PROGRAM Main VAR x : INT; END_VAR x := 1; END_PROGRAM",
                         settings=DEFAULT_SETTINGS.with_overrides([f"dialect={d.value}"])) for d in Dialect]
    from stvm.stdlib.registry import NATIVE_FBS
    from stvm.stdlib import load_natives
    load_natives()
    checked = 0
    for key, cls in NATIVE_FBS.items():
        machine = next(m for m in machines if key.lower() in m.layouts.pous._sources)
        layout = machine.layouts.pous[key.lower()]
        declared: set[str] = set()
        todo = list(layout)
        while todo:
            slot = todo.pop()
            declared.add(slot.name)
            inner = machine.layouts.of(slot.type)
            if inner is not None and inner.kind == "STRUCT":
                todo.extend(inner)
        names = getattr(cls, "__st_names__", {})
        assert names, f"{cls.__name__} declares no ST names"
        assert set(names) <= declared, (cls.__name__, set(names) - declared)
        checked += 1
    assert checked >= 9   # TON, TOF, TP and the six socket FBs


# ---------------------------------------------------------------- the contract

# Modules that generate Python code may name storage through `stvm.lower.names` themselves: the
# debugger's expression compiler is a subclass of the code generator (stvm/debug/scope.py).
CODE_GENERATORS = {"stvm/debug/scope.py"}
STORAGE_FUNCTIONS = {"var_attr", "st_name_of_attr", "is_var_attr"}


def storage_name_breaches(source: str, module: str) -> list[str]:
    """Places in `source` that build or spell a storage name by hand (`"v_" + key`, f"v_{k}",
    `obj.v_done`, `v_x=` keywords) or take the naming functions from `stvm.lower.names`."""
    found = []
    for node in ast.walk(ast.parse(source)):
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.startswith("v_"):
            found.append(f"{module}:{line}: string {node.value!r}")
        elif isinstance(node, ast.JoinedStr) and node.values and isinstance(node.values[0], ast.Constant) \
                and str(node.values[0].value).startswith("v_"):
            found.append(f"{module}:{line}: f-string building a storage name")
        elif isinstance(node, ast.Attribute) and node.attr.startswith("v_"):
            found.append(f"{module}:{line}: attribute .{node.attr}")
        elif isinstance(node, ast.keyword) and node.arg and node.arg.startswith("v_"):
            found.append(f"{module}:{line}: keyword {node.arg}=")
        elif isinstance(node, ast.ImportFrom) and node.module == "stvm.lower.names" and module not in CODE_GENERATORS:
            for alias in node.names:
                if alias.name in STORAGE_FUNCTIONS or alias.name == "*":
                    found.append(f"{module}:{line}: imports {alias.name} from stvm.lower.names")
        elif isinstance(node, (ast.Import, ast.ImportFrom)) and module not in CODE_GENERATORS:
            modules = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                      ([f"{node.module}.{a.name}" for a in node.names] if node.module == "stvm.lower" else [])
            if "stvm.lower.names" in modules:
                found.append(f"{module}:{line}: imports the module stvm.lower.names")
    return found


def test_no_module_outside_lower_builds_storage_names():
    breaches = []
    for package in ("stvm", "emulator"):
        for path in sorted((ROOT / package).rglob("*.py")):
            module = path.relative_to(ROOT).as_posix()
            if module.startswith("stvm/lower/"):
                continue
            breaches += storage_name_breaches(path.read_text(encoding="utf-8"), module)
    assert not breaches, "storage names built outside stvm/lower (read them from the layout):\n" + "\n".join(breaches)


@pytest.mark.parametrize("snippet", [
    'key = "v_" + name.lower()',
    'attr = f"v_{name}"',
    'inst.v_done = True',
    'x = getattr(obj, "v_count")',
    'SimpleNamespace(v_q=False)',
    'from stvm.lower.names import var_attr',
    'import stvm.lower.names',
    'from stvm.lower import names',
])
def test_the_contract_check_catches(snippet):
    assert storage_name_breaches(snippet, "stvm/example.py")


@pytest.mark.parametrize("snippet", [
    'value = getattr(obj, slot.storage)',
    'inst.Done = True',
    '"""docs mention v_names inside text"""',
    'from stvm.lower.names import method_attr',
    'prev_value = 1',
])
def test_the_contract_check_allows(snippet):
    assert not storage_name_breaches(snippet, "stvm/example.py")


def test_st_names_compiles_to_the_code_of_hand_written_storage_names():
    """No per-scan cost: the bound code is the code `inst.<storage name>` would compile to."""
    namespace: dict = {}
    exec(f"def by_hand(inst):\n    if not inst.{var_attr('IN')}:\n        inst.{var_attr('Q')} = False\n"
         f"    return inst.{var_attr('Q')}\n", namespace)

    @st_names("IN", "Q")
    def by_st_name(inst):
        if not inst.IN:
            inst.Q = False
        return inst.Q

    hand, bound = namespace["by_hand"].__code__, by_st_name.__code__
    assert bound.co_code == hand.co_code and bound.co_names == hand.co_names


def test_the_layout_pickles_as_its_model(vm):
    import pickle
    layouts = vm.layouts
    _ = layouts.pous["main"], layouts.globals           # built ones are not pickled
    again = pickle.loads(pickle.dumps((vm.model, layouts)))[1]
    assert again.pous["main"] == layouts.pous["main"] and again.globals == layouts.globals
    assert set(layouts.__getstate__()) == {"model"}
