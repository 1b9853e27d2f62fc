"""Deep nesting (issue 17): FB instances and calls up to NESTING_LIMIT levels run under `stvm
run` and `stvm debug` alike; deeper is a check-time error naming the chain, never a
RecursionError, however deep."""

from __future__ import annotations

import io

import pytest

from core_helpers import cli
from stvm.semantics.checker import NESTING_LIMIT


def fb_chain(levels: int) -> str:
    """PROGRAM Main holding an FB instance holding an FB instance … `levels` levels in all."""
    out = ["FUNCTION_BLOCK FB0\nVAR_OUTPUT q : INT; END_VAR\nq := q + 1;\nEND_FUNCTION_BLOCK\n"]
    for i in range(1, levels - 1):
        out.append(f"FUNCTION_BLOCK FB{i}\nVAR_OUTPUT q : INT; END_VAR\nVAR inner : FB{i - 1}; END_VAR\n"
                   f"inner();\nq := inner.q;\nEND_FUNCTION_BLOCK\n")
    out.append(f"PROGRAM Main\nVAR top : FB{levels - 2}; x : INT; END_VAR\ntop();\nx := top.q;\nEND_PROGRAM\n")
    return "".join(out)


def function_chain(levels: int) -> str:
    """PROGRAM Main calling F(levels-2), which calls … F0: `levels` levels in all."""
    out = ["FUNCTION F0 : INT\nVAR_INPUT v : INT; END_VAR\nF0 := v + 1;\nEND_FUNCTION\n"]
    for i in range(1, levels - 1):
        out.append(f"FUNCTION F{i} : INT\nVAR_INPUT v : INT; END_VAR\nF{i} := F{i - 1}(v) + 1;\nEND_FUNCTION\n")
    out.append(f"PROGRAM Main\nVAR x : INT; END_VAR\nx := F{levels - 2}(0);\nEND_PROGRAM\n")
    return "".join(out)


@pytest.mark.parametrize("make, expected", [(fb_chain, "Main.x = 1"), (function_chain, f"Main.x = {NESTING_LIMIT - 1}")],
                         ids=["fb-instances", "function-calls"])
def test_the_limit_runs_under_run_and_debug(tmp_path, make, expected):
    path = tmp_path / "deep.st"
    path.write_text(make(NESTING_LIMIT))
    rc, out, err = cli(["run", str(path), "--cycles", "1", "--print", "Main.x", "--no-cache"])
    assert (rc, out.strip()) == (0, expected), err
    from stvm.debug.console import Console
    from stvm.debug.session import SessionOptions, open_session
    session = open_session(SessionOptions([str(path)]))
    try:
        text = io.StringIO()
        Console(session.engine, io.StringIO("scan 1\nprint Main.x\n"), text).run()
    finally:
        session.close()
    assert expected in text.getvalue(), text.getvalue()


@pytest.mark.parametrize("levels", [NESTING_LIMIT + 1, 1200, 3000])
def test_deeper_fb_nesting_is_a_check_error_naming_the_chain(tmp_path, levels):
    path = tmp_path / "deep.st"
    path.write_text(fb_chain(levels))
    rc, out, err = cli(["check", str(path)])
    assert rc == 1
    assert "RecursionError" not in err and "Traceback" not in err
    assert f"FB instances and structures nested {levels} deep: Main .top (FB{levels - 2}) .inner (FB{levels - 3})" in err
    assert f"limit is {NESTING_LIMIT} levels" in err
    assert err.count("error:") == 1            # one error for the chain, at PROGRAM Main
    assert f"deep.st:{fb_chain(levels).count(chr(10)) - 4}:1: error" in err
    rc, out, err = cli(["run", str(path), "--cycles", "1"])
    assert rc == 1 and "nested" in err


def test_deeper_call_chains_are_a_check_error(tmp_path):
    path = tmp_path / "deep.st"
    path.write_text(function_chain(1000))
    rc, out, err = cli(["check", str(path)])
    assert rc == 1, err
    assert "calls nested 1000 deep: Main -> F998 -> F997" in err and "-> F0;" in err


def test_nested_structures_count_too(tmp_path):
    levels = NESTING_LIMIT + 5
    types = ["TYPE S0 : STRUCT v : INT; END_STRUCT; END_TYPE\n"]
    types += [f"TYPE S{i} : STRUCT inner : S{i - 1}; END_STRUCT; END_TYPE\n" for i in range(1, levels)]
    path = tmp_path / "deep.st"
    path.write_text("".join(types) + f"PROGRAM Main\nVAR s : S{levels - 1}; END_VAR\nEND_PROGRAM\n")
    rc, out, err = cli(["check", str(path)])
    assert rc == 1 and f"nested {levels + 1} deep: Main .s (S{levels - 1}) .inner (S{levels - 2})" in err, err
