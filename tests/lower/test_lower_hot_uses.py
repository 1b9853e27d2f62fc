"""Uses weighted by the branches they sit in (stvm/lower/hot_uses.py): an IF or CASE branch counts
once per way its statement can go, loops multiply, an FB call counts once per argument."""

from __future__ import annotations

import pytest

from stvm.lower.hot_uses import hot_uses
from stvm.project import check
from stvm.syntax.walk import LOOP_WEIGHT

SOURCE = """
FUNCTION_BLOCK Inner
VAR_INPUT a : INT; b : INT; END_VAR
END_FUNCTION_BLOCK

PROGRAM Main
VAR x : INT; y : INT; z : INT; k : INT; f : Inner; END_VAR
IF x > 0 THEN
    y := 1;
ELSIF x > 1 THEN
    y := 2;
ELSE
    z := 3;
END_IF;
CASE x OF
    1: y := 4;
ELSE
    z := 5;
END_CASE;
FOR k := 1 TO 3 DO
    z := z + 1;
END_FOR;
f(a := x, b := 2);
END_PROGRAM
"""


@pytest.fixture
def main_body(tmp_path):
    path = tmp_path / "main.st"
    path.write_text(SOURCE)
    analysis, diags, _ = check([path], use_cache=False)
    assert analysis is not None, diags
    return next(node for key, node in analysis.pou_nodes.items() if key.endswith("main")).body


def test_branches_share_their_statement_loops_multiply_fb_calls_count_their_arguments(main_body):
    uses = hot_uses(main_body)
    # IF: both conditions on every call, each of 3 ways a third; CASE: selector once, 2 ways
    assert uses["x"] == 1 + 1 + 1 + 1          # two IF conditions, the CASE selector, f's input a
    assert uses["y"] == pytest.approx(1 / 3 + 1 / 3 + 1 / 2)
    assert uses["z"] == pytest.approx(1 / 3 + 1 / 2 + 2 * LOOP_WEIGHT)
    assert uses["k"] == LOOP_WEIGHT             # the loop variable, inside its loop
    assert uses["f"] == 2 + 1                   # once per argument, once to call it


def test_the_weights_are_added_in_the_order_of_the_source(main_body):
    """Float sums depend on their order: the weights of a name are added as a walk in source
    order meets them (what the lowering's decisions were made with)."""
    uses = hot_uses(main_body)
    assert uses["y"] == 1 / 3 + 1 / 3 + 1 / 2
    assert uses["z"] == 1 / 3 + 1 / 2 + LOOP_WEIGHT + LOOP_WEIGHT
