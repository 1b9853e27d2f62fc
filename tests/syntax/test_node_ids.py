"""Stable node ids (issue 18): facts about syntax nodes are keyed by `Node.nid`, never `id(node)`."""

from __future__ import annotations

import ast
import pickle
from pathlib import Path

from stvm.syntax import nodes as n

ROOT = Path(__file__).resolve().parents[2]
# the stages that keep facts about syntax nodes
FACT_KEEPERS = [*sorted((ROOT / "stvm" / "semantics").glob("*.py")), *sorted((ROOT / "stvm" / "lower").glob("*.py")),
                ROOT / "stvm" / "debug" / "scope.py", ROOT / "stvm" / "lint" / "facts_view.py"]


def test_equal_nodes_have_distinct_ids_that_stay():
    a, b = n.IntLiteral(1), n.IntLiteral(1)
    assert b.nid == a.nid + 1   # drawn when made, in order
    assert a == b and a.nid != b.nid
    assert a.nid == a.nid


def test_a_node_read_back_from_a_pickle_is_a_new_node():
    a = n.Name(("x",))
    first = a.nid
    b = pickle.loads(pickle.dumps(a))
    assert b == a and b.nid != first and a.nid == first


def test_every_node_class_draws_an_id_when_made_and_when_read_back():
    import copy
    import dataclasses
    from stvm.source import NO_SPAN
    # Method, Accessor and Property are plain (unslotted) frozen dataclasses: their own path
    method = n.Method("M", (), None, (), (), (), NO_SPAN, NO_SPAN)
    for node in (method, n.Name(("x",))):
        again, copied = pickle.loads(pickle.dumps(node)), copy.deepcopy(node)
        replaced = dataclasses.replace(node)
        assert again == node == copied == replaced
        assert len({node.nid, again.nid, copied.nid, replaced.nid}) == 4


def test_ids_are_not_reused_after_a_node_is_freed():
    seen = set()
    for _ in range(1000):
        nid = n.IntLiteral(0).nid   # freed right away: id() would hand out the same address again
        assert nid not in seen
        seen.add(nid)


def test_the_checker_keys_its_facts_by_node_id(tmp_path):
    from stvm.project import check   # the project driver: above this stage, imported only here
    source = tmp_path / "main.st"
    source.write_text("PROGRAM Main VAR x : INT; END_VAR x := x + 1; x := x + 1; END_PROGRAM\n")
    analysis, diagnostics, _ = check([source], use_cache=False)
    assert diagnostics == []
    facts = analysis.facts
    body = analysis.pou_nodes["main"].body
    assert body[0] == body[1] and body[0].value.nid != body[1].value.nid
    assert body[0].value.nid in facts.types and body[1].value.nid in facts.types


def test_no_fact_keeper_keys_by_id():
    offenders = []
    for path in FACT_KEEPERS:
        source = path.read_text()
        lines = source.splitlines()
        for node in ast.walk(ast.parse(source)):
            # `id(x)` and `id` passed on (`map(id, calls)`)
            if isinstance(node, ast.Name) and node.id == "id" and "# not a node" not in lines[node.lineno - 1]:
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert offenders == [], "key facts about nodes by node.nid: " + ", ".join(offenders)
