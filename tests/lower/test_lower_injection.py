"""Adversarial ST: no identifier, string, comment or pragma may ever become Python code.

Every case either runs correctly (values as written) or is rejected with a diagnostic; a
sentinel file proves the payloads never executed, and the generated module never contains the
payload outside a string constant.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import stvm
from core_helpers import check_text, cli, load_st, write_st


@pytest.fixture
def sentinel(tmp_path) -> Path:
    return tmp_path / "PWNED"


def payloads(sentinel: Path) -> list[str]:
    target = str(sentinel).replace("\\", "/")
    return [
        f"'); import os; os.system('touch {target}') #",
        f"\"); __import__('pathlib').Path('{target}').touch() #",
        f"'''; __import__('pathlib').Path('{target}').touch(); '''",
        f"\"\"\"; open('{target}', 'w').close(); \"\"\"",
        f"\\'; open('{target}','w') #",
        f"{{open('{target}','w')}}",
        f"\n__import__('pathlib').Path('{target}').touch()\n",
    ]


def st_string(text: str) -> str:
    """`text` as an ST string literal ($-escaped)."""
    out = []
    for ch in text:
        if ch == "'":
            out.append("$'")
        elif ch == "$":
            out.append("$$")
        elif ch == "\n":
            out.append("$L")
        else:
            out.append(ch)
    return "'" + "".join(out) + "'"


def assert_payload_only_in_constants(project, payload: str) -> None:
    """The payload may appear in the generated module only inside str/bytes constants."""
    source = project.lowered.source
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant):
            continue
        for name in ("id", "attr", "name"):
            value = getattr(node, name, None)
            if isinstance(value, str):
                assert "import" not in value and "touch" not in value and "system" not in value


def test_string_literals_cannot_inject(sentinel):
    decls, checks = [], {}
    for i, payload in enumerate(payloads(sentinel)):
        decls.append(f"s{i} : STRING := {st_string(payload)};")
        checks[f"Main.s{i}"] = payload.encode()
    body = "\n".join(f"t{i} := CONCAT(s{i}, {st_string(p)});" for i, p in enumerate(payloads(sentinel)))
    tdecls = "\n".join(f"t{i} : STRING;" for i in range(len(payloads(sentinel))))
    src = "PROGRAM Main\nVAR\n" + "\n".join(decls) + "\n" + tdecls + "\nEND_VAR\n" + body + "\nEND_PROGRAM\n"
    project = load_st(src)
    vm = project.start()
    vm.run(cycles=2)
    for path, value in checks.items():
        assert vm[path] == value
        assert vm[path.replace(".s", ".t")] == value + value
    assert not sentinel.exists()
    for payload in payloads(sentinel):
        assert_payload_only_in_constants(project, payload)


def test_comments_and_pragmas_cannot_inject(sentinel):
    target = str(sentinel).replace("\\", "/")
    src = f"""
(* '); __import__('pathlib').Path('{target}').touch() # *)
// \"\"\" __import__('pathlib').Path('{target}').touch()
/* ''' open('{target}', 'w') ''' */
{{ __import__('pathlib').Path('{target}').touch() }}
PROGRAM Main
VAR x : INT; (* '); open('{target}','w') # *) END_VAR
x := x + 1; // '); open('{target}','w')
END_PROGRAM
"""
    vm = load_st(src).start()
    vm.run(cycles=2)
    assert vm["Main.x"] == 2
    assert not sentinel.exists()


PY_NAMES = ["class", "def", "lambda", "pass", "None", "yield", "global", "del", "import", "from",
            "print", "exec", "eval", "os", "sys", "self", "cls", "G", "T", "ctx", "Frame", "v_x", "v_v_x",
            "await", "async", "nonlocal", "assert", "raise", "try", "except", "finally", "with", "is", "in",
            "__builtins__", "__import__", "__class__", "_G", "_T", "_ctx", "_f32", "_idiv", "_copy_value",
            "__init__", "__call__", "__slots__", "_impl", "_r", "_f", "_e", "_frame"]


def _accepted_names(names: list[str]) -> list[str]:
    """The names `stvm check` accepts as variables (one file first; per name if that fails)."""
    decls = "\n".join(f"{name} : INT;" for name in names)
    body = "\n".join(f"{name} := 1;" for name in names)
    rc, err = check_text(f"PROGRAM Main\nVAR\n{decls}\nEND_VAR\n{body}\nEND_PROGRAM\n", "names_all.st")
    assert "Traceback" not in err
    if rc == 0:
        return list(names)
    accepted = []
    for name in names:
        rc, err = check_text(f"PROGRAM Main\nVAR {name} : INT; END_VAR\n{name} := 1;\nEND_PROGRAM\n",
                             f"name_{name.strip('_') or 'u'}.st")
        assert "Traceback" not in err
        assert rc in (0, 1), (name, err)
        if rc == 0:
            accepted.append(name)
        else:
            assert ": error:" in err
    return accepted


def test_python_keywords_and_helper_names_as_st_identifiers():
    """Each name is either rejected with a diagnostic or works as an ordinary variable."""
    accepted = _accepted_names(PY_NAMES)
    assert accepted, "every name rejected?"
    decls = "\n".join(f"{name} : DINT := {i};" for i, name in enumerate(accepted))
    body = "\n".join(f"{name} := {name} * 2 + 1;" for name in accepted)
    vm = load_st(f"PROGRAM Main\nVAR\n{decls}\nEND_VAR\n{body}\nEND_PROGRAM\n").start()
    vm.run(cycles=2)
    for i, name in enumerate(accepted):
        assert vm[f"Main.{name}"] == (i * 2 + 1) * 2 + 1, name


@pytest.mark.parametrize("name", ["RETURN", "return", "IF", "END_VAR", "TRUE", "MOD"])
def test_st_keywords_are_not_names(name):
    rc, err = check_text(f"PROGRAM Main\nVAR {name} : INT; END_VAR\n{name} := 1;\nEND_PROGRAM\n", "kw.st")
    assert rc == 1 and ": error:" in err and "Traceback" not in err


def test_python_names_as_pou_type_and_member_names():
    src = """
TYPE object : STRUCT dict : INT; self : INT; END_STRUCT; kind : (None, True1, self); END_TYPE
FUNCTION_BLOCK self
VAR_INPUT cls : INT; END_VAR
VAR_OUTPUT def : INT; END_VAR
def := cls + 1;
END_FUNCTION_BLOCK
FUNCTION lambda : INT
VAR_INPUT import : INT; END_VAR
lambda := import * 2;
END_FUNCTION
FUNCTION_BLOCK init
VAR_OUTPUT x : INT; END_VAR
x := 5;
END_FUNCTION_BLOCK
PROGRAM Main
VAR inst : self; r : INT; o : object; e : kind := kind#self; k : init; END_VAR
inst(cls := 41);
r := lambda(import := inst.def);
o.self := r; o.dict := 3;
k();
END_PROGRAM
"""
    path = write_st(src, "pynames.st")
    rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache", "--print", "Main.r", "--print", "Main.o",
                        "--print", "Main.e", "--print", "Main.k.x"])
    assert "Traceback" not in err
    assert rc == 0, err
    assert out.splitlines() == ["Main.r = 84", "Main.o = (dict := 3, self := 84)", "Main.e = kind#self",
                                "Main.k.x = 5"]


@pytest.mark.parametrize("length", [127, 300, 5000])
def test_very_long_identifiers(length):
    name = "n" + "x" * (length - 1)
    src = f"PROGRAM Main\nVAR {name} : INT; END_VAR\n{name} := 5;\nEND_PROGRAM\n"
    path = write_st(src, f"long_{length}.st")
    rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache", "--print", f"Main.{name}"])
    assert "Traceback" not in err
    # the source compiles or is refused with a diagnostic; a --print path over the path reader's
    # limit (1,024 characters, stvm/runtime/paths.py) is a usage error naming the limit
    assert ((rc, out) == (0, f"Main.{name} = 5\n") or (rc == 1 and ": error:" in err)
            or (rc == 2 and "stvm: error:" in err and "1024" in err.replace(",", "")))


@pytest.mark.parametrize("name", ["é", "变量", "x\u200by", "ｘ", "x\u0301", "Ω", "x·y"])
def test_unicode_identifiers_are_rejected_with_a_diagnostic(name):
    rc, err = check_text(f"PROGRAM Main\nVAR {name} : INT; END_VAR\n{name} := 1;\nEND_PROGRAM\n", "uni.st")
    assert rc == 1 and ": error:" in err and "Traceback" not in err


def test_unicode_in_strings_and_comments_runs():
    src = "PROGRAM Main\n(* ünïcode комментарий 注释 *)\nVAR s : STRING := 'héllo €'; n : UINT; END_VAR\n" \
          "// ✓ ✗\nn := LEN(s);\nEND_PROGRAM\n"
    vm = load_st(src).start()
    vm.scan()
    assert vm["Main.s"] == "héllo €".encode()
    assert vm["Main.n"] == 7


def test_user_native_pragma_is_a_diagnostic():
    src = "{native} FUNCTION Evil : INT VAR_INPUT x : INT; END_VAR END_FUNCTION\n" \
          "PROGRAM Main VAR y : INT; END_VAR y := Evil(1); END_PROGRAM\n"
    path = write_st(src, "native_user2.st")
    rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache"])
    assert rc == 1 and ": error:" in err and "Traceback" not in err


def test_set_values_cannot_inject(sentinel):
    target = str(sentinel).replace("\\", "/")
    path = write_st("PROGRAM Main\nVAR s : STRING; i : INT; END_VAR\nEND_PROGRAM\n", "set_inject.st")
    for value in [f"'); open('{target}','w') #", f"__import__('os').system('touch {target}')",
                  f"1; open('{target}','w')"]:
        for var in ("Main.s", "Main.i"):
            rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache", "--set", f"{var}={value}"])
            assert rc in (0, 2) and "Traceback" not in err
    assert not sentinel.exists()


def test_st_cannot_reach_python_builtins():
    """Names that are Python builtins resolve as ST names (undeclared → diagnostic), never as Python."""
    for call in ["x := __import__('os');", "x := eval('1');", "x := getattr(x, 'y');", "x := open('f');",
                 "x := globals();", "x := _G.v_x;", "x := self.v_x;"]:
        rc, err = check_text(f"PROGRAM Main\nVAR x : INT; END_VAR\n{call}\nEND_PROGRAM\n", "builtin.st")
        assert rc == 1 and ": error:" in err and "Traceback" not in err, (call, err)


def test_load_error_never_executes_anything(sentinel):
    target = str(sentinel).replace("\\", "/")
    src = f"PROGRAM Main\nVAR x : INT; END_VAR\nx := '); open('{target}','w') #;\nEND_PROGRAM\n"
    with pytest.raises(stvm.LoadError):
        load_st(src)
    assert not sentinel.exists()
