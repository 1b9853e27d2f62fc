"""The stdlib units shipped prebuilt (stvm/stdlib/prebuilt.py) are what the parser makes now."""

from __future__ import annotations

import dataclasses

from stvm.settings import DEFAULT_SETTINGS
from stvm.stdlib import prebuilt, stdlib_sources
from stvm.syntax.parser import parse_text


def test_the_shipped_stdlib_units_are_current_and_equal_a_fresh_parse():
    texts = stdlib_sources(DEFAULT_SETTINGS)
    shipped = prebuilt.load(texts, DEFAULT_SETTINGS)
    assert shipped is not None, ("stvm/stdlib/prebuilt_units.pickle.z is stale (grammar, parser, nodes or "
                                 "stdlib changed): rebuild it with `python -m stvm.stdlib.prebuilt`")
    units, diags = shipped
    fresh = [parse_text(text, name, DEFAULT_SETTINGS) for name, text in texts]
    assert [d for _, ds in fresh for d in ds] == diags
    assert [u for u, _ in fresh] == units                       # the trees (spans aside)
    # and the spans too (kept out of `==`)
    assert list(_spans([u for u, _ in fresh])) == list(_spans(units))


def _spans(value):
    """Every span in a tree, depth first."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            item = getattr(value, f.name)
            if f.name.endswith("span"):
                yield item
            else:
                yield from _spans(item)
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from _spans(item)
    elif isinstance(value, dict):
        for item in value.values():
            yield from _spans(item)


def test_other_settings_or_text_never_use_the_shipped_units():
    texts = stdlib_sources(DEFAULT_SETTINGS)
    other = DEFAULT_SETTINGS.with_overrides(["rtrig_first_call=no_fire"])
    assert prebuilt.load(stdlib_sources(other), other) is None
    edited = [(name, text + "\n") for name, text in texts]
    assert prebuilt.load(edited, DEFAULT_SETTINGS) is None


def test_the_shipped_stdlib_units_are_exactly_what_the_build_writes():
    # reproducible: the same inputs give the same bytes, so a rebuild after an unrelated change
    # is no change at all (and a stale file fails here with the command that fixes it)
    import subprocess
    import sys
    from pathlib import Path
    done = subprocess.run([sys.executable, "-m", "stvm.stdlib.prebuilt", "--check"],
                          cwd=Path(__file__).resolve().parents[2], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
