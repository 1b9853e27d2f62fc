"""`stvm run … --print` through references (`r^.x`), and the NULL-dereference fault (exit 3)."""

from __future__ import annotations

from core_helpers import cli, write_st

PROGRAM = """
TYPE Point : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
PROGRAM Main
VAR p : Point; r : REF_TO Point; ri : REF_TO INT; none : REF_TO INT; refy : REFERENCE TO INT; END_VAR
r := REF(p);
r^.x := r^.x + 1;
ri := REF(p.y);
refy REF= p.y;
refy := refy + 2;
END_PROGRAM
"""


def test_print_through_references():
    path = write_st(PROGRAM)
    rc, out, err = cli(["run", path, "--cycles", "3", "--print", "Main.r^.x", "--print", "Main.r^",
                        "--print", "Main.ri", "--print", "Main.none", "--print", "Main.refy"])
    assert (rc, err) == (0, "")
    assert out.splitlines() == ["Main.r^.x = 3", "Main.r^ = (x := 3, y := 6)", "Main.ri = -> 6",
                                "Main.none = NULL", "Main.refy = -> 6"]


def test_set_through_a_reference():
    path = write_st(PROGRAM)
    rc, out, err = cli(["run", path, "--cycles", "1", "--set", "Main.p.y=10", "--print", "Main.ri^"])
    assert (rc, err) == (0, "")
    assert out == "Main.ri^ = 12\n"


def test_print_through_null_is_a_usage_error():
    path = write_st(PROGRAM)
    rc, out, err = cli(["run", path, "--cycles", "1", "--print", "Main.none^"])
    assert rc == 2 and "NULL" in err and "Traceback" not in err


def test_null_dereference_exits_3_naming_line_and_scan():
    path = write_st("""PROGRAM Main
VAR r : REF_TO INT; x : INT; END_VAR
x := x + 1;
IF x > 1 THEN
    x := r^;
END_IF
END_PROGRAM
""")
    rc, out, err = cli(["run", path, "--cycles", "5"])
    assert rc == 3
    first = err.splitlines()[0]
    assert first.startswith(f"{path}:5:5: fault: dereference of a NULL reference (task ")
    assert "scan 1" in first
    assert "x := r^;" in err
