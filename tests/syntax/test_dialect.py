"""`--dialect iec|sysmac|codesys|twincat` (the `dialect` setting, `[project] dialect` in
stvm.toml): vendor name rules and vendor base types only in their dialect."""

from __future__ import annotations

import pytest

from stvm.settings import DEFAULT_SETTINGS, Dialect, SysmacSettings
from tests.core_helpers import assert_no_traceback, cli, run_st, write_st

NAMES = """PROGRAM Main
VAR _rmp : INT; p_count : INT; END_VAR
_rmp := 2; p_count := _rmp + 1;
END_PROGRAM
"""


def test_iec_is_the_default_and_sysmac_keeps_its_name_rules():
    assert DEFAULT_SETTINGS.dialect is Dialect.IEC
    rc, _, err = cli(["check", write_st(NAMES, "names.st")])
    assert rc == 0, err                       # IEC: one leading '_' and 'p_' are ordinary names
    rc, _, err = cli(["check", write_st(NAMES, "names.st"), "--dialect", "sysmac"])
    assert rc == 1
    assert "name '_rmp' may not start with '_'" in err and "name 'p_count' may not start with 'P_'" in err


@pytest.mark.parametrize("dialect", ["iec", "codesys", "twincat"])
def test_other_dialects_take_leading_underscore_and_p_names(dialect):
    assert run_st(NAMES, prints=["Main.p_count"], settings=SysmacSettings(dialect=dialect)) == {"Main.p_count": 3}
    rc, out, err = cli(["run", write_st(NAMES, "names.st"), "--dialect", dialect, "--cycles", "1",
                        "--print", "Main.p_count", "--no-cache"])
    assert (rc, out) == (0, "Main.p_count = 3\n"), err


@pytest.mark.parametrize("name, message", [("a__b", "may not contain '__' (IEC 61131-3 6.1.2)"),
                                           ("count_", "may not end with '_' (IEC 61131-3 6.1.2)")])
def test_iec_rules(name, message):
    src = f"PROGRAM Main VAR {name} : INT; END_VAR {name} := 1; END_PROGRAM\n"
    rc, _, err = cli(["check", write_st(src, "iec.st"), "--dialect", "iec"])
    assert rc == 1 and f"name '{name}' {message}" in err
    rc, _, err = cli(["check", write_st(src, "iec.st"), "--dialect", "codesys"])
    assert rc == 0, err


TWINCAT_TYPES = """PROGRAM Main
VAR
  s : T_MaxString;
  w : XWORD := 16#FFFF_FFFF_FFFF;
  w2 : __XWORD;
  i : XINT := -5;
  u : __UXINT;
  p : PVOID;
  net : T_AmsNetId := '127.0.0.1.1.1';
  n : UDINT;
END_VAR
s := 'abc';
n := MAX_STRING_LENGTH;
w2 := w;
END_PROGRAM
"""


def test_twincat_base_types_and_constants():
    values = run_st(TWINCAT_TYPES, prints=["Main.s", "Main.w2", "Main.i", "Main.net", "Main.n"],
                    settings=SysmacSettings(dialect="twincat"), fmt=True)
    assert values == {"Main.s": "'abc'", "Main.w2": "281474976710655", "Main.i": "-5",
                      "Main.net": "'127.0.0.1.1.1'", "Main.n": "255"}


@pytest.mark.parametrize("dialect", ["sysmac", "iec", "codesys"])
def test_twincat_types_exist_only_under_twincat(dialect):
    rc, _, err = cli(["check", write_st(TWINCAT_TYPES, "tc.st"), "--dialect", dialect])
    assert rc == 1 and "unknown type 'T_MaxString'" in err


def test_a_user_type_shadows_a_twincat_extra():
    src = "TYPE T_MaxString : STRING(5); END_TYPE\nPROGRAM Main VAR s : T_MaxString; END_VAR s := 'ab'; END_PROGRAM\n"
    assert run_st(src, prints=["Main.s"], settings=SysmacSettings(dialect="twincat"), fmt=True) == {"Main.s": "'ab'"}


def test_dialect_in_the_manifest(tmp_path):
    (tmp_path / "stvm.toml").write_text('[project]\ndialect = "twincat"\n', encoding="utf-8")
    (tmp_path / "Main.st").write_text(TWINCAT_TYPES, encoding="utf-8")
    rc, out, err = cli(["run", tmp_path, "--cycles", "1", "--print", "Main.n", "--no-cache"])
    assert (rc, out) == (0, "Main.n = 255\n"), err
    # the command line wins over the manifest
    rc, _, err = cli(["check", tmp_path, "--dialect", "sysmac"])
    assert rc == 1 and "unknown type 'T_MaxString'" in err


def test_an_unknown_dialect_is_a_usage_error(tmp_path):
    rc, _, err = cli(["check", write_st(NAMES, "names.st"), "--dialect", "step7"])
    assert rc == 2 and "invalid choice: 'step7'" in err
    (tmp_path / "stvm.toml").write_text('[project]\ndialect = "step7"\n', encoding="utf-8")
    (tmp_path / "Main.st").write_text(NAMES, encoding="utf-8")
    rc, _, err = cli(["check", tmp_path])
    assert rc == 2
    assert_no_traceback(err)
    assert "[project]" in err and "step7" in err and "twincat" in err
