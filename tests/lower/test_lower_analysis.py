"""The lowering's analysis pass (stvm/lower/analysis.py): facts decided before any code is written,
keyed by stable node ids, and switched off by the options."""

from __future__ import annotations

from pathlib import Path

import pytest

from core_helpers import write_st
from stvm.lower.analysis import plan_project
from stvm.lower.codegen import Lowerer
from stvm.lower.options import DEFAULT_OPTIONS, LowerOptions
from stvm.project import check, project_settings
from stvm.syntax import nodes as n
from stvm.syntax.walk import walk

THESIS = Path(__file__).resolve().parents[2] / "st_src" / "PnP_Example.st"

SOURCE = """
FUNCTION_BLOCK Acc
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT total : DINT; END_VAR
VAR i : INT; data : ARRAY[0..9] OF INT; END_VAR
FOR i := 0 TO 8 DO
  data[i + 1] := data[i] + x;
END_FOR;
FOR i := 0 TO x DO
  data[i] := 0;
END_FOR;
IF x > 0 THEN
  IF x > 1 THEN
    total := total + ABS(x);
  END_IF;
END_IF;
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : Acc; r : R_TRIG; t : TON; q : BOOL; n : INT; refd : INT; p : REF_TO INT; END_VAR
n := n + 1;
r(CLK := q);
t(IN := r.Q, PT := T#10ms);
a(x := n);
p := REF(refd);
q := NOT q;
END_PROGRAM
"""


def analysed(source: str, settings=None):
    path = write_st(source)
    settings = settings or project_settings([path])
    analysis, diags, _ = check([path], settings, use_cache=False)
    assert analysis is not None, diags
    return analysis, settings


def nodes_of(analysis, key: str, kind) -> list:
    return [x for x in walk(analysis.pou_nodes[key].body) if isinstance(x, kind)]


def test_constant_bounds_decide_the_hoisted_test_while_lowering():
    analysis, settings = analysed(SOURCE)
    lowerer = Lowerer(analysis, settings, DEFAULT_OPTIONS)
    lowerer.lower()
    constant, variable = sorted(nodes_of(analysis, "acc", n.For), key=lambda loop: loop.span.line)
    planned = lowerer.plan.range_fors
    assert planned[constant.nid].bounds == (0, 8) and planned[constant.nid].fits is True
    assert planned[variable.nid].bounds is None and planned[variable.nid].fits is None
    assert planned[variable.nid].hoisted   # tested at run time: both copies are written


def test_the_plan_holds_each_optimisation_decision_by_node_id():
    analysis, settings = analysed(SOURCE)
    plan = plan_project(analysis, settings, DEFAULT_OPTIONS)
    acc, main = plan.pous["acc"], plan.pous["main"]
    loop = min(nodes_of(analysis, "acc", n.For), key=lambda loop: loop.span.line)
    decision = plan.range_fors[loop.nid]
    assert (decision.key, decision.step, decision.start, decision.var_type.name) == ("i", 1, 0, "INT")
    assert decision.hoisted == ((0, 0, 9), (1, 0, 9))   # data[i] and data[i + 1], checked once
    assert "i" in acc.cached and {"i", "total", "data"} <= acc.assigned
    assert "refd" in main.by_reference and "refd" not in main.cached
    calls = {s.call.callee.parts[0].lower(): s.call.nid for s in nodes_of(analysis, "main", n.CallStatement)}
    assert calls["r"] in plan.inlined_fbs and calls["t"] in plan.direct_native
    assert calls["a"] not in plan.inlined_fbs and calls["a"] not in plan.direct_native
    # the statements around `ABS(x)` that catch its errors: only the assignment itself
    (call_site,) = [s for s in nodes_of(analysis, "acc", n.Assign) if s.nid in plan.catches_function_errors]
    assert isinstance(call_site.value, n.Binary)
    assert not plan.skips_on_bad_index   # array_oob is not skip_statement


def test_every_optimisation_off_plans_nothing():
    analysis, settings = analysed(SOURCE)
    plan = plan_project(analysis, settings, LowerOptions.none())
    assert not plan.range_fors and not plan.inlined_fbs and not plan.direct_native and not plan.array_refs
    assert all(not pou.cached for pou in plan.pous.values())
    assert plan.catches_function_errors   # not an optimisation: FUNCTION errors are still caught


def test_statement_flags_match_a_walk_of_each_statement():
    """The one-walk marking equals asking every statement of the thesis for its own subtree (the
    generator's former `has_native_call` / `has_index`), nested statements included."""
    settings = project_settings([THESIS], ["array_oob=skip_statement"])
    analysis, diags, _ = check([THESIS], settings, use_cache=False)
    assert analysis is not None, diags
    plan = plan_project(analysis, settings, DEFAULT_OPTIONS)
    bodies = [node.body for node in analysis.pou_nodes.values() if node is not None] \
        + [node.body for node in analysis.method_nodes.values() if node.body is not None]
    statements = [x for body in bodies for x in walk(body) if isinstance(x, n.Statement)]
    assert len(statements) > 500

    def native(s) -> bool:
        return any(isinstance(x, n.Call) and (info := analysis.facts.calls.get(x.nid)) is not None
                   and not info.is_fb and not info.oo for x in walk((s,)))
    for s in statements:
        assert (s.nid in plan.skips_on_bad_index) == any(isinstance(x, n.Index) for x in walk((s,)))
        assert (s.nid in plan.catches_function_errors) == (isinstance(s, (n.Assign, n.CallStatement))
                                                           and native(s))


@pytest.mark.parametrize("options", [DEFAULT_OPTIONS, LowerOptions.none()], ids=["default", "none"])
def test_the_generators_read_the_plan(options):
    """What the plan decides is what the code shows: one Python `range` loop per planned FOR (two
    when its bounds checks are hoisted and tested at run time: the unchecked and the checked
    copy; one when constant bounds decided the test), one direct native call per planned one."""
    analysis, settings = analysed(SOURCE)
    lowerer = Lowerer(analysis, settings, options)
    source = lowerer.lower().source
    assert source.count(" in _range") == sum(1 + (bool(d.hoisted) and d.fits is None)
                                                  for d in lowerer.plan.range_fors.values())
    assert source.count("._impl.call(v_") == len(lowerer.plan.direct_native)
