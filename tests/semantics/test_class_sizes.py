"""The checker stays split into passes (docs/architecture.md, "Checker passes"): no class in
stvm/semantics grows past 550 lines, so a pass that grows is split again rather than becoming one
large class."""

from __future__ import annotations

import ast
from pathlib import Path

import stvm.semantics

LIMIT = 550


def class_lengths() -> dict[str, int]:
    lengths = {}
    for path in sorted(Path(stvm.semantics.__file__).parent.glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                lengths[f"{path.name}:{node.name}"] = node.end_lineno - node.lineno + 1
    return lengths


def test_no_class_in_stvm_semantics_is_longer_than_550_lines():
    lengths = class_lengths()
    assert "checker.py:Checker" in lengths and "body.py:BodyChecker" in lengths
    too_long = {name: n for name, n in lengths.items() if n > LIMIT}
    assert not too_long, f"split these classes into passes or parts: {too_long}"
