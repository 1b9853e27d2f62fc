"""`Lib.ENUMERATOR`: an enumerator written with its library's namespace but without its
enumeration's name (TcUnit-Verifier's `IBaseLibrary.TYPE_BIT`), resolved in stvm/libraries.py when
exactly one enumeration of the library has it and that one is not qualified_only; and a VAR_STAT
of a library's function (its hidden global is named without the namespace's backslash)."""

from __future__ import annotations

from stvm.libraries import Library
from stvm.project import load
from stvm.settings import DEFAULT_SETTINGS, SysmacSettings
from tests.core_helpers import cli, run_st, write_files

TWINCAT = DEFAULT_SETTINGS.with_table({"dialect": "twincat"}, "test")

LIB = {
    "E_Kind.st": "TYPE E_Kind : (Small := 1, Large := 2, Twice := 3); END_TYPE\n",
    "E_Size.st": "TYPE E_Size : (Small := 10, Huge := 20); END_TYPE\n",
    "E_Mode.st": "{attribute 'qualified_only'}\nTYPE E_Mode : (Auto := 5, Manual := 6); END_TYPE\n",
    "Twice.st": "FUNCTION Twice : INT\nVAR_INPUT x : INT; END_VAR\nTwice := 2 * x;\nEND_FUNCTION\n",
}


def _load(body: str, variables: str = ""):
    lib = write_files(LIB)[0].parent
    main = f"PROGRAM Main\nVAR\n{variables}\nEND_VAR\n{body}\nEND_PROGRAM\n"
    return load(write_files({"main.st": main}), TWINCAT, use_cache=False, libraries=[Library("MyLib", lib)])


def test_the_platform_namespace_enumerator_without_its_type():
    src = """PROGRAM Main
VAR bit : IBaseLibrary.TypeClass := IBaseLibrary.TYPE_BIT; same : BOOL; END_VAR
same := bit = IBaseLibrary.TypeClass.TYPE_BIT AND IBaseLibrary.TYPE_LTIME = IBaseLibrary.TypeClass.TYPE_LTIME;
END_PROGRAM
"""
    out = run_st(src, prints=["Main.bit", "Main.same"], fmt=True, settings=SysmacSettings(dialect="twincat"))
    assert out == {"Main.bit": "TypeClass#TYPE_BIT", "Main.same": "TRUE"}


def test_a_library_enumerator_of_one_enumeration_resolves():
    vm = _load("k := MyLib.Large; h := MyLib.Huge; n := MyLib.Twice(x := 4);",
               "k : MyLib.E_Kind; h : MyLib.E_Size; n : INT;").start()
    vm.run(cycles=1)
    # Twice is both an enumerator and a function of the library: the function wins, as before
    assert (vm.format("Main.k"), vm.format("Main.h"), vm["Main.n"]) == ("E_Kind#Large", "E_Size#Huge", 8)


def test_an_ambiguous_or_qualified_only_enumerator_needs_its_type():
    lib = write_files(LIB)[0].parent
    for body, name in (("k := MyLib.Small;", "Small"), ("m := MyLib.Auto;", "Auto")):
        main = write_files({"main.st": "PROGRAM Main VAR k : MyLib.E_Kind; m : MyLib.E_Mode; END_VAR "
                                        f"{body} END_PROGRAM\n"})[0]
        rc, _, err = cli(["check", "--dialect", "twincat", "--library", f"MyLib={lib}", main])
        assert rc == 1 and f"MyLib\\{name}" in err, err


def test_a_var_stat_of_a_library_function_keeps_its_value():
    # TcUnit's TEST_FINISHED_NAMED: a VAR_STAT in a function of a library (a namespaced POU)
    lib = write_files({"Count.st": "FUNCTION Count : UINT\nVAR_STAT calls : UINT; END_VAR\n"
                                   "calls := calls + 1;\nCount := calls;\nEND_FUNCTION\n"})[0].parent
    main = write_files({"main.st": "PROGRAM Main\nVAR n : UINT; END_VAR\nn := MyLib.Count();\nEND_PROGRAM\n"})
    vm = load(main, TWINCAT, use_cache=False, libraries=[Library("MyLib", lib)]).start()
    vm.run(cycles=3)
    assert vm["Main.n"] == 3
